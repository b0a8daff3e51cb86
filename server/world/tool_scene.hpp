#pragma once
// The tool-only scene: a free spherical tool (mass, damping) that tracks the commanded pose
// under PD control, in a world of rigid planes. It is a real scene type: useful to test the
// network loop and control schemes without a robot, and it stays supported.
//
// Model/state split: ToolModel never changes during a run; ToolState holds everything that
// does. tool_step() allocates nothing and is deterministic for the same inputs.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string>

#include "server/world/events.hpp"
#include "server/world/plane.hpp"

namespace teleop::sim {

constexpr int kMaxPlanes = 8;

struct ToolModel {
  double mass_kg = 0.2;                  ///< tool mass [kg]
  double radius_m = 0.05;                ///< tool sphere radius [m]
  double kp_n_per_m = 400.0;             ///< translational PD stiffness K_ps [N/m]
  double kd_ns_per_m = 12.0;             ///< translational PD damping [N s/m]
  double kp_rot_nm_per_rad = 2.0;        ///< rotational PD stiffness [N m/rad]
  double kd_rot_nms_per_rad = 0.05;      ///< rotational PD damping [N m s/rad]
  double linear_damping_ns_per_m = 0.5;  ///< viscous damping to the world [N s/m]
  double max_force_n = 200.0;            ///< PD force saturation [N]
  Eigen::Vector3d gravity_mps2 = Eigen::Vector3d::Zero();  ///< [m/s^2]
  bool gravity_compensation = true;                        ///< the controller cancels m g
  std::array<Plane, kMaxPlanes> planes{};
  int plane_count = 0;

  /// Inertia of a solid sphere about its centre [kg m^2].
  double inertia_kgm2() const { return 0.4 * mass_kg * radius_m * radius_m; }
};

struct ToolInput {
  Eigen::Vector3d target_position_m = Eigen::Vector3d::Zero();
  Eigen::Quaterniond target_orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d target_velocity_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d target_angular_velocity_radps = Eigen::Vector3d::Zero();
  double kp_override_n_per_m = 0.0;  ///< >0 replaces model.kp_n_per_m for this step
  bool hold = false;                 ///< true: track the current position with zero velocity
  /// Force on the tool from bodies other than the planes (e.g. a deformable surface) [N].
  Eigen::Vector3d external_force_n = Eigen::Vector3d::Zero();
};

struct ToolState {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d angular_velocity_radps = Eigen::Vector3d::Zero();
  Eigen::Vector3d hold_position_m = Eigen::Vector3d::Zero();  ///< latched on entering hold
  bool was_holding = false;
  // outputs of the last step
  Eigen::Vector3d contact_force_n = Eigen::Vector3d::Zero();  ///< environment force on tool [N]
  Eigen::Vector3d control_force_n = Eigen::Vector3d::Zero();  ///< PD force applied [N]
  /// The PD part of control_force_n (saturated, without gravity compensation) [N]: the force
  /// of the tracking spring-damper between the command and the tool.
  Eigen::Vector3d tracking_force_n = Eigen::Vector3d::Zero();
  double penetration_m = 0.0;  ///< deepest plane penetration [m]
  int contact_object = -1;     ///< plane id touched, -1 none
  double sim_time_s = 0.0;
};

/// Advances the tool by dt [s] (semi-implicit Euler). No allocation.
void tool_step(const ToolModel& model, ToolState& state, const ToolInput& input, double dt);

/// tool_step() that checks the result: on a non-finite state it restores the state from
/// before the step with zero velocity and pushes a kFault event. Returns false on a fault.
bool tool_step_checked(const ToolModel& model, ToolState& state, const ToolInput& input, double dt,
                       EventQueue& events);

/// Kinetic energy of the tool [J].
double tool_kinetic_energy(const ToolModel& model, const ToolState& state);

}  // namespace teleop::sim
