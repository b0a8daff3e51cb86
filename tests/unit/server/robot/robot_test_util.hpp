#pragma once
// Shared helpers of the robot tests: the PUMA 560 scene fragment and small models inline.
#include <filesystem>
#include <string>

#include "server/robot/robot_model.hpp"

namespace teleop::sim::robot::testing {

/// deploy/scenes/robot_puma560.yaml of this source tree.
/// (TELEOP_SOURCE_DIR, not __FILE__: Ninja may name the header relative to the build folder,
/// which is not where ctest runs the test.)
inline std::string puma_path() {
  return (std::filesystem::path(TELEOP_SOURCE_DIR) / "deploy/scenes/robot_puma560.yaml").string();
}

inline RobotModel puma() { return load_robot_model_file(puma_path()); }

/// The PUMA without joint friction (for exact static balances).
inline RobotModel puma_frictionless() {
  RobotModel m = puma();
  for (int i = 0; i < m.n; ++i) {
    m.links[i].viscous_nms_per_rad = 0.0;
    m.links[i].coulomb_nm = 0.0;
  }
  return m;
}

/// A one-link compound pendulum: a uniform rod of mass 2 kg and length 0.5 m turning about a
/// horizontal axis (z0 = -y world); it hangs at q = -90 deg.
inline const char* kPendulumYaml = R"(
robot:
  name: pendulum
  base: {position_m: [0, 0, 1.0], rpy_deg: [90, 0, 0]}
  gravity_mps2: [0, 0, -9.81]
  home_deg: [-90]
  tip: {radius_m: 0.02, mass_kg: 0.0, offset_m: [0, 0, 0]}
  links:
    - name: rod
      dh: {a_m: 0.5, alpha_deg: 0, d_m: 0}
      mass_kg: 2.0
      com_m: [-0.25, 0, 0]
      inertia_kgm2: [5.3333e-4, 0.0416667, 0.0416667]
      box: {size_m: [0.5, 0.04, 0.04], center_m: [-0.25, 0, 0]}
      joint: {limits_deg: [-170, -10], torque_limit_nm: 100, kp_nm_per_rad: 100, kd_nms_per_rad: 5}
)";

}  // namespace teleop::sim::robot::testing
