#include "client/control/schemes/tdpa.hpp"

#include "client/control/schemes/laws.hpp"
#include "client/control/tuning.hpp"

namespace teleop::master {

const std::vector<ControllerParam>& TimeDomainPassivityController::parameters() {
  static const std::vector<ControllerParam> table = {
      {.key = "tdpa_base",
       .flag = "--tdpa-base",
       .help = "base law",
       .field = &ControllerParams::tdpa_base,
       .choices = {"position-position", "force-position"}},
  };
  return table;
}

SchemeTraits TimeDomainPassivityController::traits(const ControllerParams& params) {
  SchemeTraits t;
  // as its base law; the delay margin of its linear model is the base law's without the PC
  t.tunable_gains = (params.tdpa_base == "force-position" ? kTuneForceGain : kTuneMasterStiffness) |
                    kTuneMasterDamping | kTuneSlaveStiffness;
  t.position_based = params.tdpa_base == "position-position";
  t.passive_by_design = true;
  return t;
}

const std::vector<SchemeVariant>& TimeDomainPassivityController::variants() {
  static const std::vector<SchemeVariant> labels = {
      {"tdpa", [](ControllerParams& p) { p.tdpa_base = "position-position"; }},
      {"tdpa-fp", [](ControllerParams& p) { p.tdpa_base = "force-position"; }},
  };
  return labels;
}

void TimeDomainPassivityController::on_configure() {
  force_position_ = params_.tdpa_base == "force-position";
}

void TimeDomainPassivityController::on_activate(const DeviceReading& /*master*/) {
  pc_.reset();
  wanted_n_.setZero();
  remote_in_j_ = remote_out_j_ = 0.0;
}

void TimeDomainPassivityController::compute(const DeviceReading& master, const SlaveSample& slave,
                                            double dt_s, ControlOutput& out) {
  const WorkspaceMap& w = params_.workspace;
  wanted_n_ = force_position_
                  ? laws::force_position_force(w, params_.force_gain, b_m_, master, slave)
                  : laws::position_position_force(w, k_pm_, b_m_, master, slave);
  // energies travel in the slave frame: P_slave = (alpha / beta) P_master
  const double to_master = w.force_scale / w.position_scale;
  if (slave.valid && slave.passivity_session == session_) {
    remote_in_j_ = slave.tdpa.energy_in_j * to_master;
    remote_out_j_ = slave.tdpa.energy_out_j * to_master;
  }
  out.force_n = pc_.filter(wanted_n_, master.linear_velocity_mps, remote_in_j_, dt_s);
}

void TimeDomainPassivityController::finish(const DeviceReading& master,
                                           const SlaveSample& /*slave*/, double dt_s,
                                           ControlOutput& out) {
  // record what is finally applied (after saturation)
  pc_.commit(out.force_n, wanted_n_, master.linear_velocity_mps, dt_s);
  const WorkspaceMap& w = params_.workspace;
  out.command.passivity_session = session_;
  out.command.tdpa.energy_in_j = pc_.energy().in_j * (w.position_scale / w.force_scale);
}

BilateralController::PassivityStatus TimeDomainPassivityController::passivity_status() const {
  PassivityStatus s;
  s.observer_j = remote_in_j_ - pc_.energy().out_j;
  s.dissipated_j = pc_.energy().dissipated_j;
  s.alpha_ns_per_m = pc_.last_alpha();
  return s;
}

}  // namespace teleop::master
