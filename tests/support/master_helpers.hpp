#pragma once
// Shared helpers of the master-side tests (tests/unit/client).
#include <string>

#include "client/analysis/press_scenario.hpp"
#include "common/sim/tool.hpp"

namespace teleop::test {

/// A press task: scheme, environment of stiffness k [N/m] (damping 50 N s/m for a wall,
/// 5 for the sphere), controller gain and one-way delay [s].
inline teleop::master::PressScenario scenario(const std::string& scheme,
                                              teleop::master::Environment env, double k,
                                              double gain, double delay_s) {
  teleop::master::PressScenario s;
  s.scheme = scheme;
  s.environment = env;
  s.env_stiffness_n_per_m = k;
  s.env_damping_ns_per_m = env == teleop::master::Environment::kWall ? 50.0 : 5.0;
  s.gain = gain;
  s.one_way_delay_s = delay_s;
  return s;
}

/// A press scenario whose operator steps down into the object and holds (steady contact).
struct SteadyContact {
  teleop::master::PressSetup setup;
  explicit SteadyContact(const teleop::master::PressScenario& s)
      : setup(teleop::master::build_press_setup(s)) {
    setup.device.script.kind = teleop::master::ScriptKind::kStep;
    setup.device.script.start_m = Eigen::Vector3d(0.0, 0.0, 0.02);
    setup.device.script.step_m = Eigen::Vector3d(0.0, 0.0, -0.035);  // 1.5 cm below the top
    setup.device.script.step_time_s = 0.2;
    setup.device.script.tremor_amplitude_m = 0.0;
    setup.loop.duration_s = 3.0;
  }
};

/// The tool law with a wall at z = 0.5 m (k 2e4 N/m, b 50 N s/m) as its one obstacle.
inline teleop::sim::ToolModel wall_tool() {
  teleop::sim::ToolModel tool;
  teleop::sim::Obstacle wall;
  wall.kind = teleop::sim::Obstacle::Kind::kPlane;
  wall.offset_m = 0.5;
  tool.add(wall);
  return tool;
}

}  // namespace teleop::test
