#pragma once
// The slave side of time-domain passivity (tdpa), as teleop::passivity::SlavePassivityPort
// (common/control/slave_port.hpp) runs it: the master's command position and input energy ->
// AdmittancePassivityController (common/control/time_domain_passivity.hpp) -> modified command
// position/velocity; after the step the tracking force is recorded and the slave port's input
// and output energies go back. No DDS, allocation-free.
#include <Eigen/Core>

#include "common/control/schemes/tdpa_port.hpp"
#include "common/control/time_domain_passivity.hpp"

namespace teleop::passivity {

/// TDPA's slave-side law: one session of the admittance-type passivity controller.
class TdpaSlaveLaw {
 public:
  /// Starts a session with drift decay time `drift_time_constant_s` [s].
  void start(double drift_time_constant_s);
  /// Forgets the session.
  void reset();
  /// Clutch open: the command point stays where it is.
  void hold();
  /// Before the slave steps: the modified target for a tracking law f = kp (x - x_s) +
  /// kd (v - v_s); `x_s`, `v_s` are the slave's position and velocity before the step.
  void before_step(const Eigen::Vector3d& x_cmd_m, const TdpaPort::Command& cmd,
                   const Eigen::Vector3d& x_s, const Eigen::Vector3d& v_s, double kp, double kd,
                   double dt_s, Eigen::Vector3d& x_out, Eigen::Vector3d& v_out);
  /// After the step (only after a before_step() of this step): records the tracking force
  /// [N] and writes the port's energies into `out` and what the controller removed into
  /// `dissipated_j`.
  void after_step(const Eigen::Vector3d& tracking_force_n, double dt_s, TdpaPort::State& out,
                  double& dissipated_j);

  const AdmittancePassivityController& controller() const { return pc_; }

 private:
  AdmittancePassivityController pc_;
};

}  // namespace teleop::passivity
