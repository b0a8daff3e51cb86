#pragma once
// The force laws the master-side schemes share (client/control/schemes/*.cpp).
#include <Eigen/Core>
#include <algorithm>

#include "client/device/haptic_device.hpp"
#include "common/control/bilateral_types.hpp"

namespace teleop::master::laws {

/// Position-position: F_m = K_pm (x_s' - x_m) - B_m v_m (damping only before a slave sample).
inline Eigen::Vector3d position_position_force(const WorkspaceMap& w, double k_pm, double b_m,
                                               const DeviceReading& master,
                                               const SlaveSample& slave) {
  Eigen::Vector3d f = -b_m * master.linear_velocity_mps;
  if (slave.valid) f += k_pm * (w.to_master_position(slave.position_m) - master.position_m);
  return f;
}

/// Force-position: F_m = K_f beta R^T f_e - B_m v_m.
inline Eigen::Vector3d force_position_force(const WorkspaceMap& w, double k_f, double b_m,
                                            const DeviceReading& master, const SlaveSample& slave) {
  Eigen::Vector3d f = -b_m * master.linear_velocity_mps;
  if (slave.valid) f += k_f * w.to_master_force(slave.contact_force_n);
  return f;
}

/// `value` moved toward `target` by at most `step`.
inline double ramp_toward(double value, double target, double step) {
  return value < target ? std::min(target, value + step) : std::max(target, value - step);
}

}  // namespace teleop::master::laws
