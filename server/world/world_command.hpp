#pragma once
// The command the world steps on, and the one way to it from the wire and on to the tool slave:
//
//   MasterCommand --from_idl()--> SlaveCommand --to_world_command()--> WorldCommand
//                                                --tool_input()--> ToolInput (the tool's law)
//
// The server's cycle, the in-process slaves and the command fuzzer (tests/fuzz/fuzz_command.cpp)
// all go through these functions. Header-only.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "common/control/bilateral_types.hpp"
#include "common/sim/tool.hpp"

namespace teleop::sim {

/// One validated command, in the slave (world) frame.
struct WorldCommand {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< relative to home
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_velocity_radps = Eigen::Vector3d::Zero();
  double kp_override_n_per_m = 0.0;  ///< >0 overrides the slave's position gain [N/m]
  bool hold = false;                 ///< hold the current pose (watchdog, clutch)
  /// Tool slave only (experiments; never from the network): a prescribed probe. The tip is
  /// put at position_m with velocity_mps first, then the contacts are resolved along its path
  /// and the bodies step; its planes do not act on it, the bodies' reaction is its force.
  bool kinematic = false;
};

/// The world's input for a slave command (hold when it is disabled). The K_ps it carries is the
/// command's; the server's cycle clamps it to what the slave holds at its rate.
inline WorldCommand to_world_command(const SlaveCommand& c) {
  WorldCommand w;
  w.position_m = c.position_m;
  w.orientation = c.orientation;
  w.velocity_mps = c.velocity_mps;
  w.angular_velocity_radps = c.angular_velocity_radps;
  w.kp_override_n_per_m = c.position_gain_n_per_m;
  w.hold = !c.enabled;
  return w;
}

/// The tool slave's input for `cmd`, with the deformable bodies' reaction on the tip [N].
inline ToolInput tool_input(const WorldCommand& cmd, const Eigen::Vector3d& external_force_n) {
  ToolInput in;
  in.target_position_m = cmd.position_m;
  in.target_orientation = cmd.orientation;
  in.target_velocity_mps = cmd.velocity_mps;
  in.target_angular_velocity_radps = cmd.angular_velocity_radps;
  in.kp_override_n_per_m = cmd.kp_override_n_per_m;
  in.hold = cmd.hold;
  in.external_force_n = external_force_n;
  return in;
}

}  // namespace teleop::sim
