#pragma once
// The mutable half of the world and its one step (MuJoCo's mjData and mj_step):
//
//   world_step(model, data, command, dt, events)
//
// is the only way any program advances a scene: the server node (ServerCycle), the in-process
// sessions (server/node/world_slave.hpp), the experiments, the world benchmark and the world's
// unit tests. It serves every scene the loader accepts: tool-only, tool + deformable
// bodies, robot, robot + deformable bodies. One step (dt):
//   1. each body's f_ext is cleared; the tip-mesh contact of each body is updated along the
//      tip's path of the last step (eq. 8 / continuous detection), giving the force on the tip
//      and adding the equal and opposite reaction onto the body's nodes (a broad phase skips
//      bodies the tip's swept sphere cannot reach);
//   2. each body steps (mass-spring or Navier, nodes against the planes; asleep when at rest
//      and untouched);
//   3. the slave steps with the summed deformable contact force as an external tip force
//      (robot: tau = J^T gamma, eq. 4, planes acting on tip and links in ODE; tool: the law of
//      common/sim/tool.hpp, planes as its obstacles; a kinematic tool, WorldCommand::kinematic,
//      is moved to the command before step 1 instead);
//   4. outputs: tip state, total environment force on the tip (planes + bodies), penetration,
//      and contact begin/end events for every object, deformable or plane.
// Allocation-free after make_world_data(); deterministic for the same inputs. Faults (a
// non-finite state, a body that blew up) are pushed as events and handled (state restored or
// reset, force zero), never thrown.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "common/sim/events.hpp"
#include "server/robot/robot_sim.hpp"
#include "server/world/world_command.hpp"
#include "server/world/world_model.hpp"

namespace teleop::sim {

constexpr int kMaxJoints = 8;

/// State of the slave after a step.
struct WorldOutput {
  Eigen::Vector3d tip_position_m = Eigen::Vector3d::Zero();
  Eigen::Quaterniond tip_orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d tip_velocity_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d tip_angular_velocity_radps = Eigen::Vector3d::Zero();
  Eigen::Vector3d contact_force_n = Eigen::Vector3d::Zero();  ///< environment force on the tip
  Eigen::Vector3d contact_torque_nm = Eigen::Vector3d::Zero();
  double penetration_m = 0.0;  ///< contact spring compression x of F = k x [m]
  double deformation_m = 0.0;  ///< indentation of a deformable body since contact began [m]
  bool in_contact = false;
  int contact_object = -1;  ///< id of the object touched deepest, -1 none
  /// Force of the slave's tracking controller on the tip this step [N] (tool: its PD, without
  /// gravity compensation; robot: estimated as -contact_force_n, the quasi-static balance).
  Eigen::Vector3d tracking_force_n = Eigen::Vector3d::Zero();
  int joint_count = 0;
  std::array<double, kMaxJoints> q_rad{}, qd_radps{}, tau_nm{};
  double sim_time_s = 0.0;
};

/// Wall time of each part of the last world_step [us] (reported per session by the server:
/// what a step costs and where).
struct StepCost {
  double collision_us = 0.0;   ///< tip against every deformable body (trees, proxy, reaction)
  double deformable_us = 0.0;  ///< the deformable bodies' own steps
  double slave_us = 0.0;       ///< the robot (ODE) or the tool law
};

/// The changing part of one deformable body.
struct DeformableBodyData {
  deformable::DeformableState state;
  collision::TipMeshContact contact;
  collision::TipContactResult last;  ///< the contact of the last step
  /// Model fem (the body keeps the tip out itself): where the tip's centre was and the
  /// surface normal when the touch began, for the indentation since then.
  Eigen::Vector3d touch_centre_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d touch_normal = Eigen::Vector3d::UnitZ();
  /// The contact stiffness the tip meets [N/m], for the local contact model's prior and the
  /// scene description: model fem, measured on the settled body at load (probe_fem_stiffness);
  /// the other models, their contact mapping's stiffness.
  double contact_stiffness_n_per_m = 0.0;
};

struct WorldData {
  std::unique_ptr<robot::RobotSim> robot;  ///< the ODE robot (robot scenes), else null
  Eigen::Quaterniond home_orientation = Eigen::Quaterniond::Identity();  ///< robot tip at home
  ToolState tool;                                                        ///< the tool slave
  std::vector<DeformableBodyData> bodies;                ///< one per model.bodies, same order
  Eigen::Vector3d tip_prev_m = Eigen::Vector3d::Zero();  ///< tip centre before the last step
  Eigen::Vector3d deformable_force_n = Eigen::Vector3d::Zero();  ///< bodies on the tip [N]
  int plane_contact = -1;  ///< plane id the slave touched in the last step, -1 none
  StepCost cost;           ///< where the last step's time went (not part of the physics)
  WorldOutput out;
};

/// Everything that changes, at the scene's initial state. Allocates (ODE, meshes, trees).
WorldData make_world_data(const WorldModel& model);

/// The secant stiffness F / d [N/m] of a fem body pressed `depth_m` deep by a rigid tip of
/// `tip_radius_m` at its highest node (against gravity, else +z), measured on a copy of `at`:
/// the tip comes down from 2 mm above in 0.3 s and holds for 0.3 s with the velocities relaxed.
/// 0 when the body faults or is not touched.
double probe_fem_stiffness(const deformable::DeformableModel& m,
                           const deformable::DeformableState& at, const Eigen::Vector3d& gravity,
                           double tip_radius_m, double dt_s, double depth_m);

/// Puts the tool slave at rest at `position_m` [m] without a step (its clock kept) and resets
/// each body's tip contact on the body's present nodes: a jump breaks continuous detection.
/// Returns false (nothing changed) for a robot scene. Allocates (contact structures).
bool place_tool(const WorldModel& model, WorldData& data, const Eigen::Vector3d& position_m);

/// Reads the arrays the next world_step will read (each awake body's model and state, each
/// body's contact tree) into the calling core's caches, one byte per cache line; writes
/// nothing, so the step that follows computes the same bits with or without it. Allocation-
/// free. Returns the sum of the bytes read (keep it, so the reads are not elided).
std::uint64_t world_prewarm(const WorldModel& model, const WorldData& data);

/// Advances the world by dt [s] towards `cmd`. Allocation-free; events go to `events`.
void world_step(const WorldModel& model, WorldData& data, const WorldCommand& cmd, double dt_s,
                EventQueue& events);

}  // namespace teleop::sim
