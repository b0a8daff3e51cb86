#pragma once
// The slave robot's dynamics, eq. (3) M(q) qdd + C qd + G + F = tau, solved by ODE (Open
// Dynamics Engine 0.16, double precision) as in the paper, in a world of rigid planes
// (floor, walls) that neither the tip nor the links can pass through.
//
// ODE keeps its own world, so the model/state split holds as far as ODE allows: RobotModel is
// immutable; RobotSim owns the ODE world (bodies, hinges, friction motors, contact joints) and
// exposes the mutable RobotState. step() does not allocate after warm-up (see docs/robot.md and
// tests/unit/server/robot/robot_sim_test.cpp, which proves it with NoAllocScope).
//
// Joint actuation per step, all inside ODE's constraint solver (implicit, stable for any gain):
//  - the hinge motor row is the joint PD plus viscous friction:
//      lambda = kd (qd_ref + kp/kd (q_ref - q) - qd') - b qd',  |lambda| <= torque limit,
//  - a one-axis angular motor row per joint is Coulomb friction (|lambda| <= Fc, target 0),
//  - gravity and friction feed-forward are explicit hinge torques,
//  - joint limits are ODE hinge stops (joints whose range exceeds 340 deg rely on the
//    controller clamp only).
// Contacts with planes are ODE contact joints whose ERP/CFM come from the plane's stiffness k
// and damping c: ERP = h k / (h k + c), CFM = 1 / (h k + c).
#include <ode/ode.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <vector>

#include "common/sim/events.hpp"
#include "common/sim/plane.hpp"
#include "server/robot/controller.hpp"
#include "server/robot/kinematics.hpp"
#include "server/robot/robot_model.hpp"

namespace teleop::sim::robot {

/// Which ODE solver advances the world.
enum class OdeStepper : std::uint8_t {
  kWorldStep = 0,       ///< dWorldStep: direct (Dantzig LCP), accurate; the default
  kWorldQuickStep = 1,  ///< dWorldQuickStep: iterative (SOR-PGS), cheaper for big worlds
};

/// Options of the simulation (not part of the robot's physics).
struct RobotSimOptions {
  OdeStepper stepper = OdeStepper::kWorldStep;
  int quick_step_iterations = 50;        ///< SOR iterations of dWorldQuickStep
  double joint_erp = 0.2;                ///< ERP of hinge constraints (drift correction)
  double joint_cfm = 1e-9;               ///< CFM of hinge constraints
  bool link_plane_collisions = true;     ///< link boxes collide with planes (the tip always does)
  double max_joint_speed_radps = 200.0;  ///< a faster joint is a numerical fault
};

/// Mutable state and outputs of the robot simulation.
struct RobotState {
  int n = 0;
  JointVector q;             ///< joint angles [rad]
  JointVector qd;            ///< joint rates [rad/s]
  JointVector tau;           ///< actuator torque applied last step (PD + feed-forward) [N m]
  JointVector tau_gravity;   ///< gravity compensation part of tau [N m]
  JointVector tau_external;  ///< J^T gamma of the external tip wrench, eq. (4) [N m]
  Eigen::Isometry3d tip_pose = Eigen::Isometry3d::Identity();  ///< tip centre, world
  Vector6d tip_twist = Vector6d::Zero();        ///< [m/s; rad/s] at the tip centre, world
  Vector6d external_wrench = Vector6d::Zero();  ///< applied external tip wrench [N; N m]
  Eigen::Vector3d tip_contact_force_n = Eigen::Vector3d::Zero();    ///< planes on the tip [N]
  Eigen::Vector3d tip_contact_torque_nm = Eigen::Vector3d::Zero();  ///< about the tip centre
  double tip_penetration_m = 0.0;  ///< deepest tip penetration into a plane [m]
  bool tip_in_contact = false;     ///< the tip touches a plane
  int tip_contact_plane = -1;      ///< Plane::id of the deepest tip contact, -1 none
  int link_contacts = 0;           ///< contact points between link boxes and planes
  Eigen::Vector3d link_contact_force_n = Eigen::Vector3d::Zero();  ///< planes on the links [N]
  Frames frames;                                                   ///< forward kinematics of q
  Jacobian jacobian;           ///< geometric Jacobian at q (eq. 5)
  ControllerState controller;  ///< joint reference, singularity and limit flags
  JointCommand command;        ///< last joint command
  double sim_time_s = 0.0;
  std::uint64_t steps = 0;
  std::uint64_t faults = 0;  ///< numerical faults detected and recovered
};

/// Owns the ODE world of one robot and the rigid planes. Not copyable.
class RobotSim {
 public:
  /// Largest number of contact points per step.
  static constexpr int kMaxContacts = 256;
  /// Largest number of planes.
  static constexpr int kMaxPlanes = 16;

  /// Builds the ODE bodies, hinges and motors of `model` and a plane geom per plane; the robot
  /// starts at model.q_home. Calls dInitODE2(0) once per process.
  /// @throws std::invalid_argument if there are more than kMaxPlanes planes or the model has
  /// no joints (a model from load_robot_model() always has 1..kMaxJoints).
  RobotSim(const RobotModel& model, const std::vector<Plane>& planes,
           const RobotSimOptions& options = {});
  ~RobotSim();
  RobotSim(const RobotSim&) = delete;
  RobotSim& operator=(const RobotSim&) = delete;

  /// Places the robot at q0 [rad] at rest, resets the controller reference to q0.
  void reset(const JointVector& q0);

  /// Advances by dt_s [s]: controller, collision with planes, external wrench, ODE step,
  /// state read-back and fault check. Events (contact begin/end, limits, faults) go to `ev`.
  /// No allocation after the first steps (ODE's arena is reserved in the constructor).
  void step(const RobotInput& in, double dt_s, EventQueue* ev);

  const RobotState& state() const { return state_; }
  const RobotModel& model() const { return model_; }
  const RobotSimOptions& options() const { return options_; }
  /// Switches the ODE stepper (benchmarks).
  void set_stepper(OdeStepper s) { options_.stepper = s; }

  /// Time spent in the last step's ODE call (dWorldStep / dWorldQuickStep) [s].
  double last_ode_step_s() const { return last_ode_step_s_; }
  /// Time spent in the last step's collision detection [s].
  double last_collision_s() const { return last_collision_s_; }

 private:
  void make_world();
  void make_bodies();
  void make_joints(const JointVector& q_build, const Frames& f);
  void reserve_contact_arenas();
  void read_state();
  void place_bodies(const JointVector& q, const JointVector& qd);
  void collide(double dt_s);
  void actuate(const JointCommand& cmd);
  void apply_external_wrench(const RobotInput& in);
  void sum_contact_forces();
  void applied_torque(const JointCommand& cmd);
  void handle_faults(double t, EventQueue* ev);

  RobotModel model_;
  RobotSimOptions options_;
  std::vector<Plane> planes_;
  RobotState state_;

  dWorldID world_ = nullptr;
  /// The world's own step threading (ODE's default one is shared by every world of the
  /// process and breaks when two threads step worlds at once).
  dThreadingImplementationID threading_ = nullptr;
  dJointGroupID contact_group_ = nullptr;
  std::array<dBodyID, kMaxJoints> bodies_{};
  std::array<dJointID, kMaxJoints> hinges_{};
  std::array<dJointID, kMaxJoints> coulomb_{};
  std::array<dGeomID, kMaxJoints> boxes_{};
  dGeomID tip_geom_ = nullptr;
  std::array<dGeomID, kMaxPlanes> plane_geoms_{};
  std::array<double, kMaxJoints> hinge_zero_{};  ///< q at which the hinge angle reads 0
  std::array<bool, kMaxJoints> has_stops_{};

  std::array<dContactGeom, 8> scratch_{};
  std::array<dJointFeedback, kMaxContacts> feedback_{};
  std::array<int, kMaxContacts> contact_kind_{};  ///< -1: tip; >= 0: link index
  std::array<Eigen::Vector3d, kMaxContacts> contact_pos_{};
  std::array<int, kMaxContacts> contact_plane_{};
  int contact_count_ = 0;
  JointVector last_good_q_;
  double last_ode_step_s_ = 0.0;
  double last_collision_s_ = 0.0;
};

/// Rigid planes of the default scene: the floor z = 0 and a side wall y = 0.6 m (normal -y)
/// in front of the robot's reach, both with the given stiffness [N/m] and damping [N s/m].
std::vector<Plane> default_robot_planes(double stiffness_n_per_m = 1.0e5,
                                        double damping_ns_per_m = 2.0e3);

}  // namespace teleop::sim::robot
