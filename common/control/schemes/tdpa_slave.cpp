#include "common/control/schemes/tdpa_slave.hpp"

namespace teleop::passivity {

void TdpaSlaveLaw::start(double drift_time_constant_s) {
  pc_.configure(drift_time_constant_s);
  pc_.reset();
}

void TdpaSlaveLaw::reset() { pc_.reset(); }

void TdpaSlaveLaw::hold() {
  if (!pc_.started()) return;
  Eigen::Vector3d x, v;
  pc_.hold(x, v);
}

void TdpaSlaveLaw::before_step(const Eigen::Vector3d& x_cmd_m, const TdpaPort::Command& cmd,
                               const Eigen::Vector3d& x_s, const Eigen::Vector3d& v_s, double kp,
                               double kd, double dt_s, Eigen::Vector3d& x_out,
                               Eigen::Vector3d& v_out) {
  pc_.filter(x_cmd_m, cmd.energy_in_j, x_s, v_s, kp, kd, dt_s, x_out, v_out);
}

void TdpaSlaveLaw::after_step(const Eigen::Vector3d& tracking_force_n, double dt_s,
                              TdpaPort::State& out, double& dissipated_j) {
  pc_.commit(tracking_force_n, dt_s);
  out.energy_in_j = pc_.energy().in_j;
  out.energy_out_j = pc_.energy().out_j;
  dissipated_j = pc_.energy().dissipated_j;
}

}  // namespace teleop::passivity
