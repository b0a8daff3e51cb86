// The bridge's derived JSON channels (foxglove.SceneUpdate, foxglove.FrameTransforms, the page's
// plot and events) built from decoded samples, and the access token check.
#include <gtest/gtest.h>
#include <json/json.h>

#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "client/bridge/scene_json.hpp"
#include "client/bridge/ws_server.hpp"
#include "common/dds/scene_objects.hpp"

namespace teleop::bridge {
namespace {

Json::Value parse(const std::string& text) {
  Json::CharReaderBuilder b;
  std::unique_ptr<Json::CharReader> r(b.newCharReader());
  Json::Value v;
  std::string err;
  EXPECT_TRUE(r->parse(text.data(), text.data() + text.size(), &v, &err)) << err << "\n" << text;
  return v;
}

/// Every number in v is finite (jsoncpp reads "nan"/"inf" as nothing valid, so a parse check
/// plus this catches both).
bool all_finite(const Json::Value& v) {
  if (v.isDouble()) return std::isfinite(v.asDouble());
  bool ok = true;
  if (v.isArray() || v.isObject()) {
    for (const auto& c : v) ok = ok && all_finite(c);
  }
  return ok;
}

SceneDescription scene_with_floor_and_robot() {
  SceneDescription s;
  s.visual_rate_hz(30.0);
  s.tip_radius_m(0.01);
  s.joint_count(1);
  SceneObject floor;
  floor.id(100);
  floor.kind(OBJECT_PLANE);
  floor.normal({0.0, 0.0, 1.0});
  floor.offset_m(0.0);
  s.objects().push_back(floor);
  for (int i = 0; i <= 1; ++i) {
    SceneObject f;
    f.id(scene_objects::kRobotFrameIdBase + i);
    f.kind(OBJECT_ROBOT_LINK);
    f.position_m({0.0, 0.0, 0.3 * i});
    f.orientation_wxyz({1.0, 0.0, 0.0, 0.0});
    s.objects().push_back(f);
  }
  return s;
}

MeshTopology tetra_surface() {
  MeshTopology t;
  t.object_id(10);
  t.vertex_count(4);
  t.triangle_indices({0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2});
  return t;
}

MeshFrame tetra_frame(float dz) {
  MeshFrame f;
  f.object_id(10);
  f.positions_m({0.0f, 0.0f, dz, 0.1f, 0.0f, dz, 0.0f, 0.1f, dz, 0.0f, 0.0f, 0.1f + dz});
  return f;
}

TEST(SceneJson, SceneUpdateHoldsTheBodyPlanesRobotTipAndForce) {
  SceneJson s;
  EXPECT_FALSE(s.ready());
  s.set_scene(scene_with_floor_and_robot());
  ASSERT_TRUE(s.set_topology(tetra_surface()));
  ASSERT_TRUE(s.set_frame(tetra_frame(0.05f)));
  SlaveState st;
  st.tip_position_m({0.0, 0.0, 0.2});
  st.contact_force_n({0.0, 0.0, 4.0});
  st.joint_position_rad({0.5});
  ASSERT_TRUE(s.set_slave(st));
  EXPECT_TRUE(s.ready());
  EXPECT_NEAR(s.period_s(), 1.0 / 30.0, 1e-12);
  EXPECT_EQ(s.triangle_count(), 4u);

  std::string text;
  s.scene_update(text, 1'700'000'000'123'456'789ull);
  const Json::Value v = parse(text);
  EXPECT_TRUE(all_finite(v));
  ASSERT_EQ(v["entities"].size(), 3u);
  const auto& env = v["entities"][0];
  const auto& body = v["entities"][1];
  const auto& robot = v["entities"][2];
  EXPECT_EQ(env["id"].asString(), "environment");
  EXPECT_EQ(env["timestamp"]["sec"].asUInt64(), 1'700'000'000u);
  EXPECT_EQ(env["timestamp"]["nsec"].asUInt64(), 123'456'789u);
  ASSERT_EQ(env["cubes"].size(), 1u) << "the floor";
  EXPECT_NEAR(env["cubes"][0]["pose"]["position"]["z"].asDouble(), -0.001, 1e-9)
      << "the floor's top face on z = 0";
  ASSERT_EQ(body["triangles"].size(), 1u);
  EXPECT_EQ(body["triangles"][0]["points"].size(), 4u);
  EXPECT_EQ(body["triangles"][0]["indices"].size(), 12u);
  EXPECT_NEAR(body["triangles"][0]["points"][3]["z"].asDouble(), 0.15, 1e-6);
  ASSERT_EQ(robot["spheres"].size(), 1u) << "the tip";
  EXPECT_NEAR(robot["spheres"][0]["size"]["x"].asDouble(), 0.02, 1e-12);
  ASSERT_EQ(robot["lines"].size(), 1u) << "the robot's links";
  ASSERT_EQ(robot["lines"][0]["points"].size(), 3u) << "frames 0 and 1, then the tip";
  EXPECT_NEAR(robot["lines"][0]["points"][1]["z"].asDouble(), 0.3, 1e-12);
  EXPECT_NEAR(robot["lines"][0]["points"][2]["z"].asDouble(), 0.2, 1e-12);
  ASSERT_EQ(robot["arrows"].size(), 1u) << "the contact force";
  // the arrow points along +x of its pose: here the force is +z, so x maps to z
  const auto& q = robot["arrows"][0]["pose"]["orientation"];
  const double x = q["x"].asDouble(), y = q["y"].asDouble(), z = q["z"].asDouble(),
               w = q["w"].asDouble();
  EXPECT_NEAR(2 * (x * z - w * y), 1.0, 1e-6) << "the rotated x axis' z component";
  EXPECT_NEAR(
      robot["arrows"][0]["shaft_length"].asDouble() + robot["arrows"][0]["head_length"].asDouble(),
      0.04, 1e-9);
  for (const char* k : {"cubes", "cylinders", "triangles", "texts", "models"}) {
    EXPECT_TRUE(robot[k].isArray()) << k;
  }

  s.frame_transforms(text, 5);
  const Json::Value tf = parse(text);
  ASSERT_EQ(tf["transforms"].size(), 3u) << "tip, robot_0, robot_1";
  EXPECT_EQ(tf["transforms"][0]["child_frame_id"].asString(), "tip");
  EXPECT_NEAR(tf["transforms"][0]["translation"]["z"].asDouble(), 0.2, 1e-12);

  ASSERT_TRUE(s.plot(text, 5));
  const Json::Value p = parse(text);
  EXPECT_NEAR(p["force_norm_n"].asDouble(), 4.0, 1e-12);
}

TEST(SceneJson, RefusesWhatDoesNotFitAndCountsIt) {
  SceneJson s;
  s.set_scene(scene_with_floor_and_robot());
  MeshTopology bad = tetra_surface();
  bad.triangle_indices()[5] = 4;  // past the 4 vertices
  EXPECT_FALSE(s.set_topology(bad));
  EXPECT_FALSE(s.set_frame(tetra_frame(0.0f))) << "no topology for it";
  ASSERT_TRUE(s.set_topology(tetra_surface()));
  MeshFrame short_frame = tetra_frame(0.0f);
  short_frame.positions_m().pop_back();
  EXPECT_FALSE(s.set_frame(short_frame));
  MeshFrame nan_frame = tetra_frame(0.0f);
  nan_frame.positions_m()[4] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(s.set_frame(nan_frame));
  SlaveState st;
  st.contact_force_n({std::numeric_limits<double>::infinity(), 0.0, 0.0});
  EXPECT_FALSE(s.set_slave(st));
  EXPECT_EQ(s.rejected(), 5u);
  EXPECT_EQ(s.triangle_count(), 0u) << "no frame accepted yet";
  std::string text;
  EXPECT_FALSE(s.plot(text, 1)) << "no state accepted yet";
  s.scene_update(text, 1);
  EXPECT_TRUE(all_finite(parse(text)));
}

TEST(SceneJson, EventTextIsEscaped) {
  Event e;
  e.seq(3);
  e.source("server");
  e.message("a \"quoted\" \\ line\nbreak");
  const Json::Value v = parse(event_json(e));
  EXPECT_EQ(v["message"].asString(), "a \"quoted\" \\ line\nbreak");
  EXPECT_EQ(v["seq"].asUInt64(), 3u);
}

TEST(SceneJson, SchemasAreJsonWithTheirTitles) {
  EXPECT_EQ(parse(kSceneUpdateSchema)["title"].asString(), "foxglove.SceneUpdate");
  EXPECT_TRUE(parse(kSceneUpdateSchema)["properties"]["entities"]["items"]["properties"]
                                       ["triangles"]["items"]["properties"]
                                           .isMember("indices"));
  EXPECT_EQ(parse(kFrameTransformsSchema)["title"].asString(), "foxglove.FrameTransforms");
  EXPECT_EQ(parse(kPlotSchema)["title"].asString(), "teleop.bridge.Plot");
  EXPECT_EQ(parse(kEventSchema)["title"].asString(), "teleop.bridge.Event");
}

TEST(AccessToken, QueryOrBearerHeaderOnly) {
  const std::string t = "0123456789abcdef0123";
  EXPECT_TRUE(token_matches("", "/", ""));
  EXPECT_TRUE(token_matches(t, "/?token=" + t, ""));
  EXPECT_TRUE(token_matches(t, "/?a=1&token=" + t + "&b=2", ""));
  EXPECT_TRUE(token_matches(t, "/", "Bearer " + t));
  EXPECT_FALSE(token_matches(t, "/", ""));
  EXPECT_FALSE(token_matches(t, "/?token=" + t.substr(1), ""));
  EXPECT_FALSE(token_matches(t, "/?token=" + t + "x", ""));
  EXPECT_FALSE(token_matches(t, "/?tok=" + t, ""));
  EXPECT_FALSE(token_matches(t, "/", "Basic " + t));
  EXPECT_FALSE(token_matches(t, "/", "Bearer "));
}

}  // namespace
}  // namespace teleop::bridge
