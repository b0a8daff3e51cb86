#include "client/control/schemes/wave_variables.hpp"

#include <algorithm>
#include <sstream>

#include "client/control/tuning.hpp"
#include "common/control/slave_port.hpp"

namespace teleop::master {

namespace {
std::string number_text(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}
}  // namespace

SchemeTraits WaveVariablesController::traits(const ControllerParams& /*params*/) {
  SchemeTraits t;
  // the wave impedance is fixed for the session, and K_ps only derives it
  t.tunable_gains = kTuneMasterDamping;
  t.position_based = true;
  t.passive_by_design = true;
  t.linear_loop_model = false;
  return t;
}

const std::vector<ControllerParam>& WaveVariablesController::parameters() {
  using P = ControllerParams;
  static const std::vector<ControllerParam> table = {
      {.key = "wave_impedance_ns_per_m",
       .flag = "--wave-impedance",
       .unit = "N s/m",
       .help = "wave impedance b (0 = K_ps * wave_time_constant_s; clamped so that the damping "
               "the device renders, alpha beta b, stays within its max damping)",
       .field = &P::wave_impedance_ns_per_m,
       .hi = passivity::kMaxWaveImpedance},
      {.key = "wave_time_constant_s",
       .unit = "s",
       .help = "tau_b of the derived b = K_ps tau_b",
       .field = &P::wave_time_constant_s,
       .lo = 1e-4,
       .hi = 1.0},
      {.key = "wave_matched",
       .flag = "--wave-unmatched",
       .help = "the slave terminates the channel with a matching damper b (no echo)",
       .field = &P::wave_matched,
       .switch_sets = false,
       .switch_help = "no matching damper at the slave (waves reflect)"},
      {.key = "wave_filter_hz",
       .unit = "Hz",
       .help = "cutoff of the passive low-pass on the backward wave at the master (0 = off)",
       .field = &P::wave_filter_hz,
       .hi = 1000.0},
  };
  return table;
}

void WaveVariablesController::on_configure() {
  const WorkspaceMap& w = params_.workspace;
  const double derived = params_.slave_stiffness_n_per_m * params_.wave_time_constant_s;
  const double wanted =
      params_.wave_impedance_ns_per_m > 0.0 ? params_.wave_impedance_ns_per_m : derived;
  // the device renders the damping alpha beta b in free motion: keep it within the spec
  const double b_max = spec_.max_damping_ns_per_m / (w.position_scale * w.force_scale);
  b_ = std::min(wanted, b_max);
  if (!(b_ >= passivity::kMinWaveImpedance)) {
    throw config::ConfigError(
        "controller: wave impedance b = " + number_text(b_) +
        " N s/m (from wave_impedance_ns_per_m = " + number_text(params_.wave_impedance_ns_per_m) +
        ", slave_stiffness_n_per_m = " + number_text(params_.slave_stiffness_n_per_m) +
        ") is out of the allowed range " + config::range_text(passivity::kMinWaveImpedance, b_max));
  }
  port_.configure(
      b_, passivity::wave_limit(b_, passivity::kWaveLimitSpeedMps, passivity::kWaveLimitForceN),
      params_.wave_filter_hz);
}

void WaveVariablesController::on_activate(const DeviceReading& master) {
  port_.reset(params_.workspace.to_slave_position(master.position_m));
  v_energy_rx_.setZero();
}

void WaveVariablesController::compute(const DeviceReading& master, const SlaveSample& slave,
                                      double dt_s, ControlOutput& out) {
  const WorkspaceMap& w = params_.workspace;
  SlaveCommand& c = out.command;
  // the channel works in the slave frame: x and xdot of the master mapped there
  const Eigen::Vector3d xdot = w.to_slave_velocity(master.linear_velocity_mps);
  const bool have = slave.valid && slave.passivity_session == session_;
  if (have) v_energy_rx_ = slave.wave.v_energy_j;
  port_.update(c.position_m, xdot, slave.wave.v_integral, slave.wave.v_energy_j, have, dt_s);
  // the operator pushes F_m into the channel; the device renders -F_m (+ local damping)
  out.force_n = -w.to_master_force(port_.force_n()) - b_m_ * master.linear_velocity_mps;
  c.passivity_session = session_;
  c.wave.impedance_ns_per_m = b_;
  c.wave.matched = params_.wave_matched;
  c.wave.u = port_.u();
  c.wave.u_integral = port_.sent().integral;
  c.wave.u_energy_j = port_.sent().energy_j;
}

BilateralController::PassivityStatus WaveVariablesController::passivity_status() const {
  PassivityStatus s;
  // backward energy received but not (yet) used: what the receiver holds back, >= 0
  s.observer_j = (v_energy_rx_ - port_.received().used_energy_j()).sum();
  return s;
}

}  // namespace teleop::master
