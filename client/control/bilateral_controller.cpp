#include "client/control/bilateral_controller.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>

namespace teleop::master {

namespace {
std::atomic<std::uint32_t> g_session_counter{0};
}  // namespace

const std::vector<ControllerParam>& BilateralController::parameters() {
  static const std::vector<ControllerParam> none;
  return none;
}

const std::vector<SchemeVariant>& BilateralController::variants() {
  static const std::vector<SchemeVariant> none;
  return none;
}

void BilateralController::configure(const ControllerParams& params, const DeviceSpec& spec) {
  params.validate();
  params_ = params;
  spec_ = spec;
  // derive and clamp the master gains against what the device can render stably
  const double k_auto = params.workspace.position_scale * params.workspace.force_scale *
                        params.slave_stiffness_n_per_m;
  const double k = params.master_stiffness_n_per_m > 0.0 ? params.master_stiffness_n_per_m : k_auto;
  k_pm_ = std::min(k, spec.max_stiffness_n_per_m);
  b_m_ = std::min(params.master_damping_ns_per_m, spec.max_damping_ns_per_m);
  f_max_ =
      params.max_force_n > 0.0 ? std::min(params.max_force_n, spec.max_force_n) : spec.max_force_n;
  active_ = false;
  on_configure();
}

void BilateralController::retune(double k_pm, double b_m, double k_f, double k_ps) {
  k_pm_ = std::min(k_pm, spec_.max_stiffness_n_per_m);
  b_m_ = std::min(b_m, spec_.max_damping_ns_per_m);
  params_.force_gain = k_f;
  params_.slave_stiffness_n_per_m = k_ps;
}

void BilateralController::activate(const DeviceReading& master) {
  seq_ = 0;
  session_ = next_session_ != 0 ? next_session_ : ++g_session_counter;
  if (session_ == 0) session_ = ++g_session_counter;  // 0 means "none" on the wire
  next_session_ = 0;
  active_ = true;
  on_activate(master);
}

void BilateralController::deactivate() { active_ = false; }

ControlOutput BilateralController::update(const DeviceReading& master, const SlaveSample& slave,
                                          double dt_s) {
  ControlOutput out;
  out.have_slave = slave.valid;
  SlaveCommand& c = out.command;
  c.seq = ++seq_;
  c.send_time_s = master.time_s;
  c.scheme = scheme();
  c.position_gain_n_per_m = params_.slave_stiffness_n_per_m;
  const WorkspaceMap& w = params_.workspace;
  c.position_m = w.to_slave_position(master.position_m);
  c.orientation = w.rotation * master.orientation;
  if (params_.send_velocity) {
    c.velocity_mps = w.to_slave_velocity(master.linear_velocity_mps);
    c.angular_velocity_radps = w.rotation * master.angular_velocity_radps;
  }
  c.enabled = active_ && master.valid;
  if (!c.enabled) return out;  // zero force, hold command

  compute(master, slave, dt_s, out);

  // numerical fault: never pass NaN to the device
  if (!out.force_n.allFinite()) out.force_n.setZero();
  out.unsaturated_force_n = out.force_n.norm();
  if (out.unsaturated_force_n > f_max_) {
    out.force_n *= f_max_ / out.unsaturated_force_n;
    out.saturated = true;
  }
  out.torque_nm = saturate_norm(out.torque_nm, spec_.max_torque_nm);
  finish(master, slave, dt_s, out);
  c.master_force_n = w.to_slave_force(out.force_n);
  return out;
}

}  // namespace teleop::master
