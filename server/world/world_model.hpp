#pragma once
// The immutable half of the world (MuJoCo's mjModel, Pinocchio's Model): everything a scene
// file says, loaded and validated in one place (load_world_model), with nothing left to parse
// later. A WorldModel never changes during a run; WorldData (world.hpp) holds what does.
//
//   WorldModel model = load_world_model("deploy/scenes/default.yaml");   // throws ConfigError
//   WorldData data = make_world_data(model);                              // allocates
//   world_step(model, data, command, dt, events);                         // allocates nothing
//
// Slaves: a free tool (kind: tool, the law of common/sim/tool.hpp) or the 6-DoF robot in ODE
// (kind: robot). Either may touch any number of deformable bodies and the rigid planes.
#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "common/config/config.hpp"
#include "common/sim/plane.hpp"
#include "common/sim/tool.hpp"
#include "server/collision/tip_mesh_contact.hpp"
#include "server/deformable/deformable.hpp"
#include "server/deformable/model_select.hpp"
#include "server/robot/robot_model.hpp"
#include "server/robot/robot_sim.hpp"

namespace teleop::sim {

/// Which slave a scene drives.
enum class SlaveKind : std::uint8_t { kTool = 0, kRobot = 1 };

/// One deformable body of a scene: its model and its contact law with the slave's tip.
struct DeformableBodyModel {
  int object_id = 10;  ///< SceneObject id (10-99)
  deformable::DeformableModel body;
  collision::TipContactParams contact;
  /// At load (make_world_data): the body rests this long under gravity on its planes with its
  /// velocities relaxed (x 0.97 per physics step), so it starts at rest in its sagged shape
  /// instead of being dropped into it; 0: it starts as built [s].
  double settle_s = 0.0;
  /// Automatic model (`auto` in the scene): the choice, predicted cost and error in one line
  /// (published as an info event) and the full report printed at load; empty otherwise.
  std::string auto_summary, auto_report;
};

struct WorldModel {
  std::string file;                ///< where it was loaded from ("" when built in code)
  std::string name = "tool-only";  ///< scene name
  SlaveKind slave = SlaveKind::kTool;
  double physics_rate_hz = 1000.0;  ///< [Hz]
  double visual_rate_hz = 60.0;     ///< mesh frame rate [Hz]
  Eigen::Vector3d gravity_mps2{0.0, 0.0, -9.81};
  double command_timeout_s = 0.05;  ///< watchdog: hold when no valid command for this long [s]
  Eigen::Vector3d workspace_min_m{-1.5, -1.5, -0.1};  ///< commands outside are rejected [m]
  Eigen::Vector3d workspace_max_m{1.5, 1.5, 1.5};
  Eigen::Vector3d tool_start_m{0.6, 0.0, 0.7};  ///< initial tool position (tool slave) [m]
  /// The world box (`world.min_m`, `world.max_m`): every object starts inside it and the
  /// command workspace lies inside it [m].
  Eigen::Vector3d world_min_m{-10.0, -10.0, -10.0};
  Eigen::Vector3d world_max_m{10.0, 10.0, 10.0};
  ToolModel tool;                          ///< the tool slave (planes as its obstacles)
  std::optional<robot::RobotModel> robot;  ///< the robot slave (kind: robot)
  /// How ODE steps the robot (the server's defaults; `teleop_experiment robot-reach --stepper`
  /// changes the stepper).
  robot::RobotSimOptions robot_options;
  std::vector<Plane> planes;
  std::vector<DeformableBodyModel> bodies;

  bool has_robot() const { return slave == SlaveKind::kRobot; }
  /// Radius of the slave's tip sphere: the robot's own tip, or the tool [m].
  double tip_radius_m() const { return has_robot() ? robot->tip_radius_m : tool.radius_m; }
  /// Mass of the tip sphere: the robot's tip mass, or the tool's [kg].
  double tip_mass_kg() const { return has_robot() ? robot->tip_mass_kg : tool.mass_kg; }
  /// Cartesian stiffness [N/m] and damping [N s/m] of the slave's tracking law, as the
  /// passivity port and the master's defaults see it (the tool's PD; the robot's Cartesian
  /// law is tuned to the same figures).
  double tracking_kp_n_per_m() const { return tool.kp_n_per_m; }
  double tracking_kd_ns_per_m() const { return tool.kd_ns_per_m; }
};

/// Loads and validates a scene file: every field, the robot (with `include`), every
/// deformable body (mesh built, model checked), and that the scene can run: it is not empty,
/// ids are unique, every object starts inside the world box and in the free space of every
/// plane, and the physics rate is one at which every part is stable (physics_rate_problem).
/// Mesh and include errors name the scene file and the field that referenced the file.
/// @throws config::ConfigError naming the file, the field, the value and the allowed range or
/// the reason (docs/configuration.md, "What a scene may not do").
WorldModel load_world_model(const std::string& file);
/// The same from parsed YAML (`root.file()` used in messages and to resolve relative paths).
/// @throws config::ConfigError.
WorldModel parse_world_model(const config::Node& root);

/// A tool-only world built in code (no file): the tool law `tool` with its obstacles (planes,
/// also listed as the world's planes, and rigid spheres, which only a tool can meet), starting
/// at `start_m`, at `rate_hz`. The in-process sessions' press scenes are such worlds.
WorldModel tool_world_model(const ToolModel& tool, const Eigen::Vector3d& start_m,
                            double rate_hz = 1000.0);

/// Safety factor on every stability limit the rate check uses (as the deformable body's
/// automatic step, deformable::kStableStepSafety).
constexpr double kRateSafety = 0.95;

/// Why the scene cannot run at `rate_hz` (dt = 1 / rate_hz), or "" when it can:
///  - tool slave: its PD (kp, c = kd + linear damping) and each contact it meets (a spring k_c
///    and a damper c_c, both applied explicitly: the damper acts while the contact pushes,
///    approaching or leaving), integrated by semi-implicit Euler, are stable iff
///    h^2 K / m + 2 h C / m <= 4 (h w <= 2 (sqrt(1 + zeta^2) - zeta), w^2 = K / m), with
///    K = kp, C = c free and K = kp + k_c, C = c + c_c in contact;
///  - robot slave: the resolved-rate IK integrates its task error as e <- (1 - h g) e, which
///    diverges for h g > 2 (g = robot.ik.gain_per_s); the joint PD is implicit in ODE;
///  - each deformable body: the sub-steps its automatic step needs (dt / largest stable step)
///    must not exceed its max_substeps.
/// Each limit is taken with the factor kRateSafety.
std::string physics_rate_problem(const WorldModel& model, double rate_hz);
/// The largest slave position gain K_ps [N/m] a command may request (WorldCommand::
/// kp_override_n_per_m) at `rate_hz`. Tool slave: the largest kp at which
/// physics_rate_problem()'s limits of its PD still hold with the factor kRateSafety, i.e. with
/// h = dt / kRateSafety, m its mass, c its damping and each contact's spring k_c and damper c_c
/// (the planes, the deformable bodies' tip contacts, the obstacles of a tool built in code):
///   free:       h^2 kp / m + 2 h c / m <= 4
///   in contact: h^2 (kp + k_c) / m + 2 h (c + c_c) / m <= 4
/// at most kMaxPositionGainNPerM, at least 0. Robot slave (its tracking does not use K_ps):
/// kMaxPositionGainNPerM.
double max_position_gain_n_per_m(const WorldModel& model, double rate_hz);
/// The largest K_ps any command may carry [N/m] (a larger one is rejected as malformed).
constexpr double kMaxPositionGainNPerM = 1e6;
/// The lowest physics rate at which physics_rate_problem() finds nothing [Hz].
double min_physics_rate_hz(const WorldModel& model);
/// One line for each deformable body that sub-steps at `rate_hz`: its largest stable step,
/// the sub-step count and length (the load prints them).
std::vector<std::string> physics_rate_notes(const WorldModel& model, double rate_hz);
/// Reads a `deformables[i].contact` mapping. @throws config::ConfigError.
collision::TipContactParams load_tip_contact_params(const config::Node& node);

}  // namespace teleop::sim
