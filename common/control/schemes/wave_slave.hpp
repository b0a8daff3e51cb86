#pragma once
// The slave side of wave variables (wave-variables), as teleop::passivity::SlavePassivityPort
// (common/control/slave_port.hpp) runs it: the forward wave integral/energy -> WaveSlavePort
// (common/control/wave_variables.hpp) with the contact force measured at the last step ->
// desired tool position/velocity; the backward wave integral/energy go back. No DDS,
// allocation-free.
#include <Eigen/Core>

#include "common/control/schemes/wave_port.hpp"
#include "common/control/wave_variables.hpp"

namespace teleop::passivity {

/// Wave variables' slave-side law: one session of the slave's wave port.
class WaveSlaveLaw {
 public:
  /// Starts a session with the command's impedance b (1 N s/m where it is not positive) and
  /// termination.
  void start(const WavePort::Command& cmd);
  /// Forgets the session.
  void reset();
  /// Before the slave steps: the target position/velocity from the forward wave, `x_cmd_m`
  /// (the master's mapped position) and the contact force of the last step [N]; writes the
  /// backward wave into `out` and what the port removed into `dissipated_j`.
  void before_step(const WavePort::Command& cmd, const Eigen::Vector3d& x_cmd_m,
                   const Eigen::Vector3d& contact_force_n, double dt_s, Eigen::Vector3d& x_out,
                   Eigen::Vector3d& v_out, WavePort::State& out, double& dissipated_j);

  const WaveSlavePort& port() const { return port_; }

 private:
  WaveSlavePort port_;
};

}  // namespace teleop::passivity
