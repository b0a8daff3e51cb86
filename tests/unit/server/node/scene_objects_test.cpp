#include "server/node/scene_objects.hpp"

#include <gtest/gtest.h>

#include "common/dds/scene_objects.hpp"
#include "server/robot/kinematics.hpp"

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

}  // namespace
}  // namespace teleop::server
