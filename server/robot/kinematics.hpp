#pragma once
// Kinematics and static maps of the slave chain (paper eqs. (4)-(6)), independent of ODE.
// Free functions over (RobotModel, q); all allocation-free (fixed-capacity Eigen types).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>

#include "server/robot/robot_model.hpp"

namespace teleop::sim::robot {

/// Output of forward_kinematics: every DH frame in the world plus the tip centre pose.
struct Frames {
  int n = 0;
  /// T[0] = frame 0 (base), T[i] = frame i (attached to link i), world frame.
  std::array<Eigen::Isometry3d, kMaxJoints + 1> T{};
  /// World position of each link's centre of mass [m] (com[i] for link i+1).
  std::array<Eigen::Vector3d, kMaxJoints> com{};
  /// Tip sphere centre pose: position = T[n] * tool_offset, orientation of frame n.
  Eigen::Isometry3d tip = Eigen::Isometry3d::Identity();
};

/// Transform of frame i relative to frame i-1 for joint value q [rad] (standard DH).
Eigen::Isometry3d dh_transform(const DhParams& dh, double q_rad);

/// Forward kinematics: fills all frames, link COMs and the tip pose for q [rad] (size n).
void forward_kinematics(const RobotModel& model, const JointVector& q, Frames& out);

/// Geometric Jacobian of the tip centre, eq. (5): column i = [z_{i-1} x (P - P_{i-1}); z_{i-1}]
/// with P the tip centre; 6 x n, world frame. Uses frames from forward_kinematics.
void geometric_jacobian(const RobotModel& model, const Frames& frames, Jacobian& J);
/// Convenience: forward kinematics then the Jacobian.
void geometric_jacobian(const RobotModel& model, const JointVector& q, Jacobian& J);

/// Tip twist v = [p_dot; w] = J qd, eq. (6) ([m/s]; [rad/s]).
Vector6d tip_twist(const Jacobian& J, const JointVector& qd);

/// Joint torques equivalent to a wrench acting on the tip, eq. (4):
/// tau = J^T gamma, gamma = [f [N]; m [N m]] applied at the tip centre, world frame.
void wrench_to_joint_torque(const Jacobian& J, const Vector6d& wrench, JointVector& tau);

/// Joint torques [N m] that hold the chain against gravity at `frames` (G(q) of eq. (3)):
/// tau_g = -sum_i J_{c,i}^T m_i g.
void gravity_torque(const RobotModel& model, const Frames& frames, JointVector& tau);

/// Pose error of (p, R) against the target (p_d, R_d): [p_d - p; rotation vector of R_d R^T]
/// ([m]; [rad]), world frame.
Vector6d pose_error(const Eigen::Vector3d& p_d, const Eigen::Matrix3d& R_d,
                    const Eigen::Vector3d& p, const Eigen::Matrix3d& R);

/// World pose of each link's box (centre and link axes) at `frames`, for drawing and for the
/// scene description (box extents are model.links[i].box_size_m). out[i] is link i+1's box.
void link_box_poses(const RobotModel& model, const Frames& frames,
                    std::array<Eigen::Isometry3d, kMaxJoints>& out);

/// Rotation vector (axis * angle [rad]) of a rotation matrix, robust near 0 and pi.
Eigen::Vector3d rotation_vector(const Eigen::Matrix3d& R);

}  // namespace teleop::sim::robot
