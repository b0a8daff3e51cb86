#include "client/viewer/robot_skeleton.hpp"

#include "common/dds/scene_objects.hpp"

namespace teleop::viewer {

bool skeleton_from_scene(const SceneDescription& scene, RobotSkeleton& out) {
  out.joints = 0;
  const int n = static_cast<int>(scene.joint_count());
  if (n <= 0 || n > kMaxSkeletonJoints) return false;
  std::array<bool, kMaxSkeletonJoints + 1> found{};
  for (const auto& o : scene.objects()) {
    if (o.kind() != OBJECT_ROBOT_LINK) continue;
    const int i = o.id() - scene_objects::kRobotFrameIdBase;
    if (i < 0 || i > n) continue;
    const auto& p = o.position_m();
    const auto& r = o.orientation_wxyz();
    Eigen::Quaterniond q(r[0], r[1], r[2], r[3]);
    if (!(q.norm() > 0.5)) return false;  // not a rotation (or NaN)
    q.normalize();
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = q.toRotationMatrix();
    T.translation() = Eigen::Vector3d(p[0], p[1], p[2]);
    if (!T.matrix().allFinite()) return false;
    out.home[static_cast<std::size_t>(i)] = T;
    out.names[static_cast<std::size_t>(i)] = o.name();
    found[static_cast<std::size_t>(i)] = true;
  }
  for (int i = 0; i <= n; ++i) {
    if (!found[static_cast<std::size_t>(i)]) return false;
  }
  out.joints = n;
  return true;
}

void skeleton_frames(const RobotSkeleton& skeleton, const double* q, int nq,
                     std::array<Eigen::Isometry3d, kMaxSkeletonJoints + 1>& frames) {
  // G accumulates R_1(q_1) ... R_i(q_i); R_j turns about the z axis of frame j-1 at q = 0
  Eigen::Isometry3d g = Eigen::Isometry3d::Identity();
  frames[0] = skeleton.home[0];
  for (int i = 1; i <= skeleton.joints; ++i) {
    const Eigen::Isometry3d& axis_frame = skeleton.home[static_cast<std::size_t>(i - 1)];
    const double qi = (q != nullptr && i - 1 < nq) ? q[i - 1] : 0.0;
    const Eigen::Vector3d p = axis_frame.translation();
    Eigen::Isometry3d r = Eigen::Isometry3d::Identity();
    r.linear() = Eigen::AngleAxisd(qi, axis_frame.linear().col(2)).toRotationMatrix();
    r.translation() = p - r.linear() * p;
    g = g * r;
    frames[static_cast<std::size_t>(i)] = g * skeleton.home[static_cast<std::size_t>(i)];
  }
}

}  // namespace teleop::viewer
