// Loading and validation of the `robot:` scene mapping.
#include "server/robot/robot_model.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "tests/unit/server/robot/robot_test_util.hpp"

namespace teleop::sim::robot {
namespace {

using teleop::config::ConfigError;
using teleop::config::Node;

TEST(RobotModel, LoadsThePuma560SceneFragment) {
  const RobotModel m = testing::puma();
  EXPECT_EQ(m.name, "puma560");
  EXPECT_EQ(m.n, 6);
  EXPECT_NEAR(m.links[1].mass_kg, 17.4, 1e-12);
  EXPECT_NEAR(m.links[1].dh.a_m, 0.4318, 1e-12);
  EXPECT_NEAR(m.links[2].dh.alpha_rad, -M_PI / 2, 1e-12);
  EXPECT_NEAR(m.tip_radius_m, 0.05, 1e-12);
  // the 0.1 kg tip sphere is folded into link 6 (0.09 kg)
  EXPECT_NEAR(m.links[5].mass_kg, 0.19, 1e-12);
  EXPECT_NEAR(m.links[5].com_m.z(), (0.09 * 0.032 + 0.1 * 0.2) / 0.19, 1e-12);
  EXPECT_NEAR(m.links[0].q_min_rad, -160.0 * M_PI / 180.0, 1e-12);
  EXPECT_NEAR(m.links[0].viscous_nms_per_rad, 5.80, 1e-12);
  EXPECT_NEAR(m.q_home(1), 78.0 * M_PI / 180.0, 1e-12);
}

TEST(RobotModel, CombineMassesUsesParallelAxisTheorem) {
  double m;
  Eigen::Vector3d c;
  Eigen::Matrix3d I;
  combine_masses(1.0, Eigen::Vector3d(-1, 0, 0), Eigen::Matrix3d::Zero(), 1.0,
                 Eigen::Vector3d(1, 0, 0), Eigen::Matrix3d::Zero(), m, c, I);
  EXPECT_DOUBLE_EQ(m, 2.0);
  EXPECT_LT(c.norm(), 1e-15);
  EXPECT_NEAR(I(0, 0), 0.0, 1e-15);
  EXPECT_NEAR(I(1, 1), 2.0, 1e-15);
  EXPECT_NEAR(I(2, 2), 2.0, 1e-15);
}

std::string expect_error(const std::string& yaml) {
  try {
    load_robot_model(Node::parse(yaml, "scene.yaml").at("robot"));
  } catch (const ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no ConfigError for:\n" << yaml;
  return "";
}

std::string pendulum_with(const std::string& from, const std::string& to) {
  std::string y = testing::kPendulumYaml;
  const auto pos = y.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  return y.replace(pos, from.size(), to);
}

TEST(RobotModel, PendulumLoads) {
  const RobotModel m = load_robot_model(Node::parse(testing::kPendulumYaml).at("robot"));
  EXPECT_EQ(m.n, 1);
  EXPECT_NEAR(m.q_home(0), -M_PI / 2, 1e-12);
}

TEST(RobotModel, RejectsBadValuesNamingFileFieldAndRange) {
  std::string e = expect_error(pendulum_with("mass_kg: 2.0", "mass_kg: -2.0"));
  EXPECT_NE(e.find("scene.yaml"), std::string::npos) << e;
  EXPECT_NE(e.find("robot.links[0].mass_kg"), std::string::npos) << e;
  EXPECT_NE(e.find("-2.0"), std::string::npos) << e;
  EXPECT_NE(e.find("range"), std::string::npos) << e;

  e = expect_error(pendulum_with("limits_deg: [-170, -10]", "limits_deg: [10, -10]"));
  EXPECT_NE(e.find("limits_deg"), std::string::npos) << e;

  e = expect_error(pendulum_with("radius_m: 0.02", "radus_m: 0.02"));
  EXPECT_NE(e.find("radus_m"), std::string::npos) << e;

  e = expect_error(pendulum_with("[5.3333e-4, 0.0416667, 0.0416667]", "[1.0, 0.01, 0.01]"));
  EXPECT_NE(e.find("triangle"), std::string::npos) << e;

  e = expect_error(pendulum_with("[5.3333e-4, 0.0416667, 0.0416667]", "[0.0, 0.04, 0.04]"));
  EXPECT_NE(e.find("inertia_kgm2"), std::string::npos) << e;

  e = expect_error(pendulum_with("home_deg: [-90]", "home_deg: [0]"));
  EXPECT_NE(e.find("home_deg"), std::string::npos) << e;

  e = expect_error(pendulum_with("kd_nms_per_rad: 5", "kd_nms_per_rad: abc"));
  EXPECT_NE(e.find("not a number"), std::string::npos) << e;

  e = expect_error(
      pendulum_with("      box: {size_m: [0.5, 0.04, 0.04], center_m: [-0.25, 0, 0]}\n", ""));
  EXPECT_NE(e.find("box"), std::string::npos) << e;

  e = expect_error("robot:\n  links: []\n  tip: {radius_m: 0.05}\n");
  EXPECT_NE(e.find("links"), std::string::npos) << e;
}

TEST(RobotModel, MeshWithoutBoxSetsTheBoxFromItsBounds) {
  const auto dir = std::filesystem::temp_directory_path() / "teleop_robot_mesh_test";
  std::filesystem::create_directories(dir);
  {
    std::ofstream obj(dir / "rod.obj");
    obj << "v -0.5 -0.02 -0.03\nv 0 -0.02 -0.03\nv 0 0.02 0.03\nv -0.5 0.02 0.03\n"
           "f 1 2 3\nf 1 3 4\n";
  }
  std::string y = pendulum_with("      box: {size_m: [0.5, 0.04, 0.04], center_m: [-0.25, 0, 0]}\n",
                                "      mesh: {file: rod.obj, scale: 1.0}\n");
  const std::string file = (dir / "scene.yaml").string();
  {
    std::ofstream f(file);
    f << y;
  }
  const RobotModel m = load_robot_model_file(file);
  EXPECT_NEAR(m.links[0].box_size_m.x(), 0.5, 1e-6);
  EXPECT_NEAR(m.links[0].box_size_m.y(), 0.04, 1e-6);
  EXPECT_NEAR(m.links[0].box_size_m.z(), 0.06, 1e-6);
  EXPECT_NEAR(m.links[0].box_center_m.x(), -0.25, 1e-6);
  EXPECT_FALSE(m.links[0].mesh_file.empty());

  std::string bad =
      pendulum_with("      box: {size_m: [0.5, 0.04, 0.04], center_m: [-0.25, 0, 0]}\n",
                    "      mesh: {file: missing.obj}\n");
  {
    std::ofstream f(file);
    f << bad;
  }
  EXPECT_THROW(load_robot_model_file(file), ConfigError);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace teleop::sim::robot
