#include "server/world/world_model.hpp"

#include <gtest/gtest.h>

namespace teleop::sim {
namespace {

std::string error_of(const std::string& yaml) {
  try {
    parse_world_model(config::Node::parse(yaml, "scene.yaml"));
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(Scene, ShippedScenesLoad) {
  for (const char* f : {"default.yaml", "tool_only.yaml"}) {
    const WorldModel s = load_world_model(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/" + f);
    EXPECT_GT(s.physics_rate_hz, 0.0) << f;
    EXPECT_GE(s.planes.size(), 1u) << f;
  }
}

TEST(Scene, ParsesPlanesAndToolParameters) {
  const WorldModel s = parse_world_model(config::Node::parse(R"(
name: t
physics: {rate_hz: 2000, gravity_mps2: [0, 0, 0]}
tool: {mass_kg: 0.5, kp_n_per_m: 800}
planes:
  - {name: floor, normal: [0, 0, 2], offset_m: 0.1}
)",
                                                             "scene.yaml"));
  EXPECT_EQ(s.physics_rate_hz, 2000.0);
  EXPECT_EQ(s.tool.mass_kg, 0.5);
  EXPECT_EQ(s.tool.kp_n_per_m, 800.0);
  ASSERT_EQ(s.planes.size(), 1u);
  EXPECT_DOUBLE_EQ(s.planes[0].normal.norm(), 1.0);
  EXPECT_EQ(s.tool.obstacle_count, 1);
}

TEST(Scene, OutOfRangeValueNamesFileFieldValueAndRange) {
  const std::string msg = error_of("physics: {rate_hz: 0.5}");
  EXPECT_NE(msg.find("scene.yaml"), std::string::npos) << msg;
  EXPECT_NE(msg.find("physics.rate_hz"), std::string::npos) << msg;
  EXPECT_NE(msg.find("0.5"), std::string::npos) << msg;
  EXPECT_NE(msg.find("[10, 20000]"), std::string::npos) << msg;
}

TEST(Scene, RejectsTyposZeroNormalsAndEmptyWorkspaces) {
  EXPECT_NE(error_of("tool: {mass: 1}").find("tool.mass"), std::string::npos);
  EXPECT_NE(error_of("planes: [{normal: [0, 0, 0]}]").find("planes[0].normal"), std::string::npos);
  EXPECT_NE(error_of("command: {workspace_min_m: [0, 0, 1], workspace_max_m: [1, 1, 1]}")
                .find("workspace_min_m"),
            std::string::npos);
  EXPECT_NE(error_of("kind: robot").find("robot"), std::string::npos);
  EXPECT_NE(error_of("kind: spaceship").find("spaceship"), std::string::npos);
}

}  // namespace
}  // namespace teleop::sim
