// The scene file's plain fields, declared once (server/world/scene_params.hpp): the loader
// reads each with its table's range and default, refuses a value past either end naming the
// file, the field path, the value and the range, and the docs' table is printed from the same
// entries.
#include "server/world/scene_params.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "server/deformable/body_params.hpp"
#include "server/robot/ik_params.hpp"
#include "server/world/world_model.hpp"
#include "tests/support/config_error.hpp"

namespace teleop::sim {
namespace {

using config::FieldParam;

/// Where a table's mapping sits in a scene, and a scene around it.
struct Section {
  std::string path;  ///< field path of the mapping ("tool", "planes[0]")
  std::string yaml;  ///< a scene with "@" where the mapping's entries go
};

const Section kWorld{"world", "world: {@}\n"};
const Section kPhysics{"physics", "physics: {@}\n"};
const Section kCommand{"command", "command: {@}\n"};
const Section kTool{"tool", "tool: {@}\n"};
const Section kPlane{"planes[0]", "planes:\n  - {normal: [0, 0, 1], @}\n"};
const Section kBody{"deformables[0].body",
                    "planes:\n  - {normal: [0, 0, 1]}\n"
                    "deformables:\n"
                    "  - body: {model: fem, level: 1, @}\n"};
const Section kContact{"deformables[0].contact",
                       "planes:\n  - {normal: [0, 0, 1]}\n"
                       "deformables:\n"
                       "  - body: {level: 1, radius_m: 0.25, centre_m: [0.6, 0, 0.25]}\n"
                       "    contact: {@}\n"};

std::string scene(const Section& s, const std::string& entry) {
  std::string y = s.yaml;
  y.replace(y.find('@'), 1, entry);
  return y;
}

WorldModel load(const std::string& yaml) {
  return parse_world_model(config::Node::parse(yaml, "scene.yaml"));
}

template <class S>
std::string value_text(const FieldParam<S>& f, double v) {
  const std::string x = f.integer != nullptr ? std::to_string(static_cast<long long>(v))
                                             : config::param_number_text(v);
  return f.point != nullptr ? "[" + x + ", " + x + ", " + x + "]" : x;
}

/// Each number or point field past either end of its range is refused by the loader, the
/// message naming the file, the field path and the range.
template <class S>
void expect_ends_refused(const Section& s, const std::vector<FieldParam<S>>& table) {
  for (const FieldParam<S>& f : table) {
    if (f.flag != nullptr) continue;
    const double span = f.hi - f.lo;
    for (const double v : {f.lo - 0.5 * span - 1.0, f.hi + 0.5 * span + 1.0}) {
      const std::string m =
          test::config_error_of([&] { load(scene(s, f.key + ": " + value_text(f, v))); });
      EXPECT_NE(m.find("scene.yaml"), std::string::npos) << m;
      EXPECT_NE(m.find("'" + s.path + "." + f.key), std::string::npos) << f.key << ": " << m;
      EXPECT_NE(m.find(config::range_text(f.lo, f.hi)), std::string::npos) << f.key << ": " << m;
    }
  }
}

TEST(SceneParams, EachTableHasUniqueKeysOneAccessorAndARange) {
  auto check = [](const auto& table) {
    std::set<std::string> keys;
    for (const auto& f : table) {
      EXPECT_TRUE(keys.insert(f.key).second) << f.key;
      EXPECT_EQ((f.number != nullptr) + (f.integer != nullptr) + (f.flag != nullptr) +
                    (f.point != nullptr),
                1)
          << f.key;
      if (f.flag == nullptr) {
        EXPECT_LT(f.lo, f.hi) << f.key;
      }
      EXPECT_FALSE(f.help.empty()) << f.key;
    }
  };
  check(world_box_params());
  check(physics_params());
  check(command_params());
  check(tool_params());
  check(plane_params());
  check(tip_contact_params());
  check(deformable::body_field_params());
  check(robot::ik_field_params());
}

TEST(SceneParams, TheLoaderRefusesEachFieldPastEitherEndOfItsRange) {
  expect_ends_refused(kWorld, world_box_params());
  expect_ends_refused(kPhysics, physics_params());
  expect_ends_refused(kCommand, command_params());
  expect_ends_refused(kTool, tool_params());
  expect_ends_refused(kPlane, plane_params());
  expect_ends_refused(kContact, tip_contact_params());
  expect_ends_refused(kBody, deformable::body_field_params());
}

TEST(SceneParams, AFieldTheFileGivesIsSetAndTheOthersKeepTheirDefaults) {
  const WorldModel d;
  const WorldModel w = load(
      "physics: {visual_rate_hz: 30}\n"
      "tool: {kd_rot_nms_per_rad: 0.02, gravity_compensation: false}\n"
      "planes:\n  - {normal: [0, 0, 2], friction: 0.7}\n"
      "deformables:\n"
      "  - body: {level: 1, radius_m: 0.25, centre_m: [0.6, 0, 0.25], max_substeps: 32,\n"
      "           friction: false}\n"
      "    contact: {patch_blend: 0.4, friction_static: 0.3, friction_kinetic: 0.2}\n");
  EXPECT_EQ(w.visual_rate_hz, 30.0);
  EXPECT_EQ(w.physics_rate_hz, d.physics_rate_hz);
  EXPECT_EQ(w.tool.kd_rot_nms_per_rad, 0.02);
  EXPECT_FALSE(w.tool.gravity_compensation);
  EXPECT_EQ(w.tool.mass_kg, d.tool.mass_kg);
  ASSERT_EQ(w.planes.size(), 1u);
  EXPECT_EQ(w.planes[0].friction, 0.7);
  EXPECT_EQ(w.planes[0].normal, Eigen::Vector3d::UnitZ());
  EXPECT_EQ(w.planes[0].stiffness_n_per_m, Plane{}.stiffness_n_per_m);
  ASSERT_EQ(w.bodies.size(), 1u);
  EXPECT_EQ(w.bodies[0].contact.patch_blend, 0.4);
  EXPECT_EQ(w.bodies[0].body.params.max_substeps, 32);
  EXPECT_FALSE(w.bodies[0].body.params.friction);
  EXPECT_EQ(w.bodies[0].body.params.cg_max_iterations,
            deformable::DeformableParams{}.cg_max_iterations);
  EXPECT_EQ(w.bodies[0].contact.node_stiffness_n_per_m,
            collision::TipContactParams{}.node_stiffness_n_per_m);
}

TEST(SceneParams, TheRobotsIkFieldsAreReadWithTheirTableAndUnits) {
  // the PUMA's robot mapping with ik fields set: a value in range is set (degrees into
  // radians), one past either end is refused naming the field and the range in degrees
  const std::string file = std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/robot_puma560.yaml";
  auto robot_with = [&](const std::string& key, const std::string& value) {
    const config::Node root = config::Node::load_file(file);
    YAML::Node r = root.raw()["robot"];
    r["ik"][key] = value;
    return robot::load_robot_model(config::Node(r, file, "robot"));
  };
  EXPECT_NEAR(robot_with("limit_margin_deg", "2").ik.limit_margin_rad, 2.0 * M_PI / 180.0, 1e-15);
  EXPECT_EQ(robot_with("gain_per_s", "25").ik.gain_per_s, 25.0);
  for (const auto& f : robot::ik_field_params()) {
    for (const double v : {f.lo - 1.0, f.hi * 2.0 + 1.0}) {
      const std::string m =
          test::config_error_of([&] { robot_with(f.key, config::param_number_text(v)); });
      EXPECT_NE(m.find("'robot.ik." + f.key + "'"), std::string::npos) << m;
      EXPECT_NE(m.find(config::range_text(f.lo, f.hi)), std::string::npos) << m;
    }
  }
  EXPECT_NE(
      scene_params_markdown().find("| `robot.ik.limit_margin_deg` | deg | 1.14592 | [0, 30] |"),
      std::string::npos);
}

TEST(SceneParams, UnknownKeysAreRefusedWithTheKnownOnes) {
  const std::string m = test::config_error_of([] { load("tool: {mass: 1}\n"); });
  EXPECT_NE(m.find("'tool.mass'"), std::string::npos) << m;
  EXPECT_NE(m.find("mass_kg"), std::string::npos) << m;
  const std::string p = test::config_error_of(
      [] { load("planes:\n  - {normal: [0, 0, 1], stiffnes_n_per_m: 1}\n"); });
  EXPECT_NE(p.find("stiffnes_n_per_m"), std::string::npos) << p;
}

TEST(SceneParams, TheDocsTableHasARowPerFieldWithItsDefaultAndRange) {
  const std::string md = scene_params_markdown();
  EXPECT_NE(md.find("| `physics.rate_hz` | Hz | 1000 | [10, 20000] |"), std::string::npos) << md;
  EXPECT_NE(md.find("| `tool.start_position_m` | m | [0.6, 0, 0.7] | each in [-100, 100] |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| `planes[].stiffness_n_per_m` | N/m | 20000 | [1, 1e8] |"), std::string::npos)
      << md;
  std::size_t rows = 0;
  for (std::size_t at = md.find("\n| `"); at != std::string::npos; at = md.find("\n| `", at + 1)) {
    ++rows;
  }
  EXPECT_EQ(rows, world_box_params().size() + physics_params().size() + command_params().size() +
                      tool_params().size() + plane_params().size() + tip_contact_params().size() +
                      deformable::body_field_params().size() + robot::ik_field_params().size());
}

}  // namespace
}  // namespace teleop::sim
