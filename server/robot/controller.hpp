#pragma once
// Slave controller: the tip tracks a commanded pose. A damped-least-squares inverse kinematics
// (resolved rate with variable damping) integrates a joint reference q_ref that a joint PD
// (gain K_ps, paper Fig. 10) tracks, with gravity and friction feed-forward. Near
// singularities the damping grows (the reference slows instead of blowing up), at joint limits
// the reference is clamped; both raise EventKind::kLimit events once on entry.
//
// Independent of ODE; allocation-free and deterministic (controller_update).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

#include "common/sim/events.hpp"
#include "server/robot/kinematics.hpp"
#include "server/robot/robot_model.hpp"

namespace teleop::sim::robot {

/// What the slave controller does this step.
enum class ControlMode : std::uint8_t {
  kTrackPose = 0,    ///< tip tracks target pose (+ optional twist feed-forward)
  kHold = 1,         ///< keep the current joint reference, zero reference velocity
  kJointTarget = 2,  ///< move the joint reference toward target_q at the speed limits
  kPassive = 3,      ///< no PD: only friction (and gravity compensation if asked)
};

/// Input of one robot step.
struct RobotInput {
  ControlMode mode = ControlMode::kTrackPose;
  Eigen::Vector3d target_position_m = Eigen::Vector3d::Zero();  ///< tip centre, world [m]
  Eigen::Quaterniond target_orientation = Eigen::Quaterniond::Identity();   ///< world
  Eigen::Vector3d target_velocity_mps = Eigen::Vector3d::Zero();            ///< feed-forward [m/s]
  Eigen::Vector3d target_angular_velocity_radps = Eigen::Vector3d::Zero();  ///< [rad/s]
  bool track_orientation = true;     ///< false: position only (3-row task)
  JointVector target_q;              ///< kJointTarget goal [rad] (size n)
  bool gravity_compensation = true;  ///< add G(q) feed-forward
  double gain_scale = 1.0;           ///< scales K_ps (Kd by its square root), (0, 10]
  /// External wrench on the tip from contact with the deformable body (computed elsewhere),
  /// world frame, at the tip centre: force [N] and torque [N m].
  Eigen::Vector3d external_force_n = Eigen::Vector3d::Zero();
  Eigen::Vector3d external_torque_nm = Eigen::Vector3d::Zero();
};

/// Joint-level command produced by the controller for one step.
struct JointCommand {
  JointVector q_ref;        ///< position reference [rad]
  JointVector qd_ref;       ///< velocity reference [rad/s]
  JointVector kp;           ///< PD stiffness this step [N m/rad]
  JointVector kd;           ///< PD damping this step [N m s/rad]
  JointVector tau_ff;       ///< feed-forward torque: gravity + friction [N m]
  JointVector tau_gravity;  ///< the gravity part of tau_ff [N m]
};

/// Mutable controller state (all storage inline; reset with controller_reset).
struct ControllerState {
  JointVector q_ref;   ///< joint reference [rad]
  JointVector qd_ref;  ///< reference velocity [rad/s]
  Frames ref_frames;   ///< forward kinematics of q_ref
  Jacobian ref_jacobian;
  double sigma_min_m = 0.0;  ///< smallest weighted singular value of J at q_ref [m]
  double damping_m = 0.0;    ///< DLS damping used last step [m]
  bool near_singular = false;
  std::uint32_t limit_mask = 0;  ///< bit i: joint i's reference is clamped at a limit
  std::uint64_t limit_events = 0;
  std::uint64_t singular_events = 0;
  bool speed_clamped = false;  ///< the joint-speed limit scaled the reference last step
};

/// Starts the reference at q (zero velocity), clears flags.
void controller_reset(const RobotModel& model, ControllerState& state, const JointVector& q);

/// One controller step: advances the joint reference from `in` and fills `out` (PD gains and
/// feed-forward at the measured q). Events (kLimit) go to `ev` if not null. No allocation.
void controller_update(const RobotModel& model, ControllerState& state, const RobotInput& in,
                       const JointVector& q, const Frames& measured_frames, double dt_s,
                       double sim_time_s, EventQueue* ev, JointCommand& out);

/// Joint PD + feed-forward torque evaluated explicitly (for reporting and for integrators
/// other than ODE's implicit motor rows): kp (q_ref - q) + kd (qd_ref - qd) + tau_ff,
/// clamped to the torque limits [N m].
void joint_torque(const RobotModel& model, const JointCommand& cmd, const JointVector& q,
                  const JointVector& qd, JointVector& tau);

}  // namespace teleop::sim::robot
