#include "common/control/schemes/wave_slave.hpp"

namespace teleop::passivity {

void WaveSlaveLaw::start(const WavePort::Command& cmd) {
  const double b = cmd.impedance_ns_per_m > 0.0 ? cmd.impedance_ns_per_m : 1.0;
  port_.configure(b, cmd.matched, wave_limit(b, kWaveLimitSpeedMps, kWaveLimitForceN));
  port_.reset();
}

void WaveSlaveLaw::reset() { port_.reset(); }

void WaveSlaveLaw::before_step(const WavePort::Command& cmd, const Eigen::Vector3d& x_cmd_m,
                               const Eigen::Vector3d& contact_force_n, double dt_s,
                               Eigen::Vector3d& x_out, Eigen::Vector3d& v_out, WavePort::State& out,
                               double& dissipated_j) {
  port_.update(cmd.u_integral, cmd.u_energy_j, x_cmd_m, contact_force_n, dt_s);
  x_out = port_.position_m();
  v_out = port_.velocity_mps();
  out.v = port_.v();
  out.v_integral = port_.sent().integral;
  out.v_energy_j = port_.sent().energy_j;
  dissipated_j = port_.dissipated_j();
}

}  // namespace teleop::passivity
