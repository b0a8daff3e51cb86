// The viewer poses the robot from the scene description's frames at q = 0 and the joint
// positions: it must agree with the server's own forward kinematics.
#include "client/viewer/robot_skeleton.hpp"

#include <gtest/gtest.h>

#include <random>

#include "common/dds/scene_objects.hpp"
#include "server/node/scene_objects.hpp"
#include "server/robot/kinematics.hpp"
#include "server/robot/robot_model.hpp"

namespace teleop::viewer {
namespace {

sim::robot::RobotModel puma() {
  return sim::robot::load_robot_model_file(std::string(TELEOP_SOURCE_DIR) +
                                           "/deploy/scenes/robot_puma560.yaml");
}

TEST(RobotSkeleton, MatchesTheServersForwardKinematicsAtAnyPose) {
  const sim::robot::RobotModel model = puma();
  SceneDescription scene;
  scene.joint_count(static_cast<std::uint32_t>(model.n));
  server::append_robot_frames(model, scene);
  ASSERT_EQ(scene.objects().size(), static_cast<std::size_t>(model.n + 1));
  RobotSkeleton sk;
  ASSERT_TRUE(skeleton_from_scene(scene, sk));
  EXPECT_EQ(sk.joints, 6);
  EXPECT_EQ(sk.names[0], "base");
  EXPECT_EQ(sk.names[2], "upper_arm");

  std::mt19937 rng(3);
  std::uniform_real_distribution<double> angle(-3.0, 3.0);
  std::array<Eigen::Isometry3d, kMaxSkeletonJoints + 1> frames;
  for (int trial = 0; trial < 20; ++trial) {
    sim::robot::JointVector q(model.n);
    for (int i = 0; i < model.n; ++i) q(i) = trial == 0 ? model.q_home(i) : angle(rng);
    sim::robot::Frames fk;
    sim::robot::forward_kinematics(model, q, fk);
    skeleton_frames(sk, q.data(), model.n, frames);
    for (int i = 0; i <= model.n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      EXPECT_LT((frames[k].translation() - fk.T[k].translation()).norm(), 1e-9)
          << "trial " << trial << " frame " << i;
      EXPECT_LT((frames[k].linear() - fk.T[k].linear()).norm(), 1e-9);
    }
    // the tip is the tool offset from the last frame
    const Eigen::Vector3d tip = frames[6] * model.tool_offset_m;
    EXPECT_LT((tip - fk.tip.translation()).norm(), 1e-9);
  }
}

TEST(RobotSkeleton, TipOnlyWhenTheSceneHasNoOrIncompleteFrames) {
  SceneDescription scene;
  scene.joint_count(6);
  RobotSkeleton sk;
  EXPECT_FALSE(skeleton_from_scene(scene, sk));  // an older server: joints but no frames
  EXPECT_EQ(sk.joints, 0);
  server::append_robot_frames(puma(), scene);
  scene.objects().erase(scene.objects().begin() + 3);
  EXPECT_FALSE(skeleton_from_scene(scene, sk));
  SceneDescription tool;
  EXPECT_FALSE(skeleton_from_scene(tool, sk));  // tool-only scene
}

}  // namespace
}  // namespace teleop::viewer
