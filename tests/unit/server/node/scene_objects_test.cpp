#include "server/node/scene_objects.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "common/dds/scene_objects.hpp"
#include "common/util/version.hpp"
#include "server/robot/kinematics.hpp"
#include "server/world/world_model.hpp"

namespace teleop::server {
namespace {

TEST(SceneObjects, RobotFramesAreTheChainAtZeroJointAngles) {
  const auto model = sim::robot::load_robot_model_file(std::string(TELEOP_SOURCE_DIR) +
                                                       "/deploy/scenes/robot_puma560.yaml");
  SceneDescription scene;
  append_robot_frames(model, scene);
  ASSERT_EQ(scene.objects().size(), static_cast<std::size_t>(model.n + 1));
  sim::robot::Frames fk;
  sim::robot::forward_kinematics(model, sim::robot::JointVector::Zero(model.n), fk);
  for (int i = 0; i <= model.n; ++i) {
    const SceneObject& o = scene.objects()[static_cast<std::size_t>(i)];
    EXPECT_EQ(o.id(), scene_objects::kRobotFrameIdBase + i);
    EXPECT_EQ(o.kind(), OBJECT_ROBOT_LINK);
    const auto& p = o.position_m();
    const auto& r = o.orientation_wxyz();
    const Eigen::Quaterniond q(r[0], r[1], r[2], r[3]);
    EXPECT_NEAR(q.norm(), 1.0, 1e-12);
    EXPECT_LT((Eigen::Vector3d(p[0], p[1], p[2]) - fk.T[static_cast<std::size_t>(i)].translation())
                  .norm(),
              1e-12);
    EXPECT_LT((q.toRotationMatrix() - fk.T[static_cast<std::size_t>(i)].linear()).norm(), 1e-12);
  }
  EXPECT_EQ(std::string(scene.objects()[0].name()), "base");
  EXPECT_EQ(std::string(scene.objects()[1].name()), model.links[0].name);
  EXPECT_DOUBLE_EQ(scene.objects()[2].mass_kg(), model.links[1].mass_kg);
  // the base stands where the scene file puts it
  EXPECT_NEAR(scene.objects()[0].position_m()[2], 0.672, 1e-12);
}

/// The deformable objects of the description of the scene in `file`.
std::vector<SceneObject> deformables_of(const std::string& file) {
  const sim::WorldModel model = sim::load_world_model(file);
  const sim::WorldData data = sim::make_world_data(model);
  const SceneDescription d = describe_scene(model, data, model.physics_rate_hz);
  std::vector<SceneObject> out;
  for (const SceneObject& o : d.objects()) {
    if (o.kind() == OBJECT_DEFORMABLE_MESH) {
      out.push_back(o);
    } else {
      EXPECT_EQ(o.substeps(), 0u);  // only deformables say anything about their step
    }
  }
  return out;
}

// The automatic step is in the scene description: the highest natural frequency of each body,
// its integrator's stable step, and the sub-steps it takes per physics step.
TEST(SceneObjects, DeformablesPublishTheirStableStepAndSubSteps) {
  const auto def = deformables_of(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/default.yaml");
  ASSERT_EQ(def.size(), 1u);
  EXPECT_GT(def[0].highest_frequency_radps(), 100.0);
  EXPECT_GT(def[0].stable_step_s(), 1e-3);  // the default scene runs at 0.92 of its limit
  EXPECT_EQ(def[0].substeps(), 1u);

  // ten times stiffer than stable at 1 ms: it sub-steps, and says how much
  const std::string file =
      (std::filesystem::temp_directory_path() / "scene_objects_stiff.yaml").string();
  std::ofstream(file) << "planes:\n  - {name: floor, normal: [0, 0, 1]}\n"
                         "deformables:\n  - body: {level: 1, radius_m: 0.25, centre_m: [0.6, 0, "
                         "0.25], edge_stiffness_n_per_m: 50000}\n";
  const auto stiff = deformables_of(file);
  std::filesystem::remove(file);
  ASSERT_EQ(stiff.size(), 1u);
  EXPECT_LT(stiff[0].stable_step_s(), 1e-3);
  EXPECT_GT(stiff[0].stable_step_s(), 0.0);
  EXPECT_EQ(stiff[0].substeps(),
            static_cast<std::uint32_t>(std::ceil(1e-3 / stiff[0].stable_step_s() - 1e-9)));
  EXPECT_GT(stiff[0].substeps(), 1u);
}

}  // namespace
}  // namespace teleop::server

namespace teleop::server {
namespace {

TEST(SceneObjects, AFemBallSettledAtLoadIsDescribedByItsSaggedTop) {
  // default.yaml: settle_s 3, the foam ball of radius 0.25 m resting on the floor
  const sim::WorldModel model =
      sim::load_world_model(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/default.yaml");
  ASSERT_EQ(model.bodies.size(), 1u);
  EXPECT_GT(model.bodies[0].settle_s, 0.0);
  const sim::WorldData data = sim::make_world_data(model);
  const Eigen::Matrix3Xd& x = data.bodies[0].state.x;
  const double top = x.row(2).maxCoeff();
  EXPECT_LT(top, 0.5 - 0.015);  // it starts sagged (24 mm under its weight) ...
  EXPECT_GT(top, 0.5 - 0.035);
  EXPECT_LT(data.bodies[0].state.v.colwise().norm().maxCoeff(), 0.01);  // ... and at rest
  const SceneDescription scene = describe_scene(model, data, 1000.0);
  bool found = false;
  for (const SceneObject& o : scene.objects()) {
    if (o.kind() != OBJECT_DEFORMABLE_MESH) continue;
    found = true;
    EXPECT_NEAR(o.position_m()[2] + o.size_m()[1], top, 1e-12);  // where a tip from above lands
    EXPECT_GE(o.size_m()[0], o.size_m()[1]);                     // inside its bounding sphere
  }
  EXPECT_TRUE(found);
}

TEST(SceneObjects, TheDescriptionSaysWhichBuildMadeIt) {
  const sim::WorldModel model =
      sim::load_world_model(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/tool_only.yaml");
  const sim::WorldData data = sim::make_world_data(model);
  const SceneDescription scene = describe_scene(model, data, 1000.0);
  EXPECT_EQ(std::string(scene.build_version()), version_string());
  EXPECT_EQ(std::string(scene.build_version()).rfind(std::string(project_version()) + " (git ", 0),
            0u)
      << scene.build_version();
}

}  // namespace
}  // namespace teleop::server
