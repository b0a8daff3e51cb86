#pragma once
// The slave law of a free spherical tool: the one law behind the server's tool-only scene, the
// tool slave of tool + deformable scenes, and so of the in-process slave of the master-side
// tests and the delay sweep (server/node/world_slave.hpp steps the same world).
//
// A tool of mass m and radius r tracks the commanded pose under a saturated PD (K_ps, B_ps,
// velocity feed-forward, optional gravity compensation) and meets penalty obstacles:
//   - planes (floor, walls):   f = max(0, k d - ramp(d) b v_n) n,  d = r - (n . x - offset)
//   - spheres (a soft ball):   the same law, n the outward normal, d = R + r - |x - c|
// with the damping ramped in over the first kPlaneDampingRampM of depth, so the force is
// continuous at contact onset. Obstacles are summed in the order they were added.
//
// Model/state split: ToolModel never changes during a run; ToolState holds everything that
// does. tool_step() allocates nothing and is deterministic for the same inputs.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>

#include "common/sim/events.hpp"
#include "common/sim/plane.hpp"

namespace teleop::sim {

/// A penalty contact primitive of the tool's environment.
struct Obstacle {
  enum class Kind : std::uint8_t { kPlane, kSphere } kind = Kind::kPlane;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();   ///< plane: unit normal into free space
  double offset_m = 0.0;                               ///< plane: normal . x = offset [m]
  Eigen::Vector3d centre_m = Eigen::Vector3d::Zero();  ///< sphere: centre [m]
  double radius_m = 0.25;                              ///< sphere: radius [m]
  double stiffness_n_per_m = 2.0e4;                    ///< k [N/m]
  double damping_ns_per_m = 50.0;                      ///< b (compression only) [N s/m]
  int id = 0;                                          ///< object id reported on contact

  /// The obstacle of a scene plane (same id, normal, offset, stiffness and damping).
  static Obstacle of(const Plane& p) {
    Obstacle o;
    o.kind = Kind::kPlane;
    o.normal = p.normal;
    o.offset_m = p.offset_m;
    o.stiffness_n_per_m = p.stiffness_n_per_m;
    o.damping_ns_per_m = p.damping_ns_per_m;
    o.id = p.id;
    return o;
  }
};

struct ToolModel {
  static constexpr int kMaxObstacles = 8;

  double mass_kg = 0.2;                  ///< tool mass m_s [kg]
  double radius_m = 0.05;                ///< tool sphere radius [m]
  double kp_n_per_m = 400.0;             ///< translational PD stiffness K_ps [N/m]
  double kd_ns_per_m = 12.0;             ///< translational PD damping B_ps [N s/m]
  double kp_rot_nm_per_rad = 2.0;        ///< rotational PD stiffness [N m/rad]
  double kd_rot_nms_per_rad = 0.05;      ///< rotational PD damping [N m s/rad]
  double linear_damping_ns_per_m = 0.5;  ///< b_s, viscous damping to the world [N s/m]
  double max_force_n = 200.0;            ///< PD force saturation [N]
  Eigen::Vector3d gravity_mps2 = Eigen::Vector3d::Zero();  ///< [m/s^2]
  bool gravity_compensation = true;                        ///< the controller cancels m g
  std::array<Obstacle, kMaxObstacles> obstacles{};
  int obstacle_count = 0;

  /// Appends an obstacle (at most kMaxObstacles). Returns false when full.
  bool add(const Obstacle& o) {
    if (obstacle_count >= kMaxObstacles) return false;
    obstacles[static_cast<std::size_t>(obstacle_count++)] = o;
    return true;
  }
  /// Inertia of a solid sphere about its centre [kg m^2].
  double inertia_kgm2() const { return 0.4 * mass_kg * radius_m * radius_m; }
};

struct ToolInput {
  Eigen::Vector3d target_position_m = Eigen::Vector3d::Zero();
  Eigen::Quaterniond target_orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d target_velocity_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d target_angular_velocity_radps = Eigen::Vector3d::Zero();
  double kp_override_n_per_m = 0.0;  ///< >0 replaces model.kp_n_per_m for this step
  bool hold = false;                 ///< true: track the latched position with zero velocity
  /// Force on the tool from bodies other than the obstacles (e.g. a deformable surface) [N].
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
  Eigen::Vector3d contact_force_n = Eigen::Vector3d::Zero();  ///< obstacles' force on tool [N]
  Eigen::Vector3d control_force_n = Eigen::Vector3d::Zero();  ///< PD force applied [N]
  /// The PD part of control_force_n (saturated, without gravity compensation) [N]: the force
  /// of the tracking spring-damper between the command and the tool.
  Eigen::Vector3d tracking_force_n = Eigen::Vector3d::Zero();
  double penetration_m = 0.0;  ///< deepest obstacle penetration [m]
  int contact_object = -1;     ///< obstacle id touched deepest, -1 none
  double sim_time_s = 0.0;
};

/// A tool at rest at `position_m` (hold latch there too), time zero.
ToolState tool_state_at(const Eigen::Vector3d& position_m);

/// Advances the tool by dt [s] (semi-implicit Euler). No allocation.
void tool_step(const ToolModel& model, ToolState& state, const ToolInput& input, double dt);

/// tool_step() that checks the result: on a non-finite state it restores the state from
/// before the step with zero velocity and pushes a kFault event. Returns false on a fault.
bool tool_step_checked(const ToolModel& model, ToolState& state, const ToolInput& input, double dt,
                       EventQueue& events);

/// Kinetic energy of the tool [J].
double tool_kinetic_energy(const ToolModel& model, const ToolState& state);

}  // namespace teleop::sim
