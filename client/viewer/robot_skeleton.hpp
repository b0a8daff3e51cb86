#pragma once
// The slave robot as the viewer draws it: a skeleton through the chain's frame origins, posed
// from SlaveState.joint_position_rad. The frames at q = 0 come from the scene description
// (OBJECT_ROBOT_LINK objects, see common/dds/scene_objects.hpp); joint j turns about the z
// axis of frame j-1, so the frames at any q follow by the product of exponentials.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string>

#include "teleop/idl/Teleop.h"

namespace teleop::viewer {

/// Joints the viewer can pose (SlaveState carries at most 16).
inline constexpr int kMaxSkeletonJoints = 16;

struct RobotSkeleton {
  int joints = 0;  ///< 0: no robot, or no frames in the scene description
  std::array<Eigen::Isometry3d, kMaxSkeletonJoints + 1> home{};  ///< frames 0..joints at q = 0
  std::array<std::string, kMaxSkeletonJoints + 1> names{};
};

/// Reads the robot's frames from a scene description. Returns false (and joints = 0) when the
/// scene has joints but not all of frames 0..joint_count, or frames but no joints.
bool skeleton_from_scene(const SceneDescription& scene, RobotSkeleton& out);

/// World poses of frames 0..joints at joint positions q [rad] (nq values; missing ones count
/// as 0). Allocation-free.
void skeleton_frames(const RobotSkeleton& skeleton, const double* q, int nq,
                     std::array<Eigen::Isometry3d, kMaxSkeletonJoints + 1>& frames);

}  // namespace teleop::viewer
