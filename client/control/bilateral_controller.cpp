#include "client/control/bilateral_controller.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <sstream>

#include "common/control/slave_port.hpp"

namespace teleop::master {

using config::ConfigError;

namespace {
void check(const char* field, double v, double lo, double hi) {
  config::check_range("controller", field, v, lo, hi);
}

std::string joined_names() {
  std::string s;
  for (const auto& n : controller_names()) s += (s.empty() ? "" : ", ") + n;
  return s;
}

std::atomic<std::uint32_t> g_session_counter{0};
}  // namespace

void ControllerParams::validate() const {
  const auto& names = controller_names();
  if (std::find(names.begin(), names.end(), scheme) == names.end()) {
    throw ConfigError("controller: scheme '" + scheme + "' is unknown (allowed: " + joined_names() +
                      ")");
  }
  if (tdpa_base != "position-position" && tdpa_base != "force-position") {
    throw ConfigError("controller: tdpa_base '" + tdpa_base +
                      "' is unknown (allowed: position-position, force-position)");
  }
  check("wave_impedance_ns_per_m", wave_impedance_ns_per_m, 0.0, passivity::kMaxWaveImpedance);
  check("mmt_blend_s", mmt_blend_s, 1e-4, 1.0);
  check("contact_damping_ramp_s", contact_damping_ramp_s, 1e-4, 10.0);
  check("mmt_energy_rate_w", mmt_energy_rate_w, 0.0, 10.0);
  check("mmt_energy_burst_j", mmt_energy_burst_j, 0.0, 1.0);
  check("wave_time_constant_s", wave_time_constant_s, 1e-4, 1.0);
  check("wave_filter_hz", wave_filter_hz, 0.0, 1000.0);
  check("slave_stiffness_n_per_m", slave_stiffness_n_per_m, 0.0, 1e6);
  check("master_stiffness_n_per_m", master_stiffness_n_per_m, 0.0, 1e6);
  check("master_damping_ns_per_m", master_damping_ns_per_m, 0.0, 1e4);
  check("force_gain", force_gain, 0.0, 100.0);
  check("max_force_n", max_force_n, 0.0, 1e4);
  check("workspace.position_scale", workspace.position_scale, 1e-3, 1e3);
  check("workspace.force_scale", workspace.force_scale, 1e-3, 1e3);
  if (!workspace.offset_m.allFinite())
    throw ConfigError("controller: workspace.offset_m not finite");
}

ControllerParams controller_params_from_yaml(const config::Node& node) {
  ControllerParams p;
  if (!node.defined()) return p;
  node.reject_unknown_keys({"scheme", "workspace", "slave_stiffness_n_per_m",
                            "master_stiffness_n_per_m", "master_damping_ns_per_m", "force_gain",
                            "max_force_n", "send_velocity", "wave_impedance_ns_per_m",
                            "wave_time_constant_s", "wave_matched", "wave_filter_hz", "tdpa_base",
                            "mmt_blend_s", "mmt_energy_rate_w", "mmt_energy_burst_j",
                            "contact_damping_ramp_s"});
  p.scheme = node.choice_or("scheme", p.scheme, controller_names());
  p.slave_stiffness_n_per_m =
      node.number_or("slave_stiffness_n_per_m", p.slave_stiffness_n_per_m, 0.0, 1e6);
  p.master_stiffness_n_per_m =
      node.number_or("master_stiffness_n_per_m", p.master_stiffness_n_per_m, 0.0, 1e6);
  p.master_damping_ns_per_m =
      node.number_or("master_damping_ns_per_m", p.master_damping_ns_per_m, 0.0, 1e4);
  p.force_gain = node.number_or("force_gain", p.force_gain, 0.0, 100.0);
  p.max_force_n = node.number_or("max_force_n", p.max_force_n, 0.0, 1e4);
  p.send_velocity = node.boolean_or("send_velocity", p.send_velocity);
  p.wave_impedance_ns_per_m = node.number_or("wave_impedance_ns_per_m", p.wave_impedance_ns_per_m,
                                             0.0, passivity::kMaxWaveImpedance);
  p.wave_time_constant_s =
      node.number_or("wave_time_constant_s", p.wave_time_constant_s, 1e-4, 1.0);
  p.wave_matched = node.boolean_or("wave_matched", p.wave_matched);
  p.wave_filter_hz = node.number_or("wave_filter_hz", p.wave_filter_hz, 0.0, 1000.0);
  p.tdpa_base = node.choice_or("tdpa_base", p.tdpa_base, {"position-position", "force-position"});
  p.mmt_blend_s = node.number_or("mmt_blend_s", p.mmt_blend_s, 1e-4, 1.0);
  p.contact_damping_ramp_s =
      node.number_or("contact_damping_ramp_s", p.contact_damping_ramp_s, 1e-4, 10.0);
  p.mmt_energy_rate_w = node.number_or("mmt_energy_rate_w", p.mmt_energy_rate_w, 0.0, 10.0);
  p.mmt_energy_burst_j = node.number_or("mmt_energy_burst_j", p.mmt_energy_burst_j, 0.0, 1.0);
  if (node.has("workspace")) {
    const config::Node w = node.at("workspace");
    w.reject_unknown_keys({"offset_m", "position_scale", "force_scale"});
    const auto off = w.numbers_or("offset_m", {0.0, 0.0, 0.0}, -1e3, 1e3);
    if (off.size() != 3) w.fail("offset_m", "must be a list of 3 numbers [x, y, z]");
    p.workspace.offset_m = Eigen::Vector3d(off[0], off[1], off[2]);
    p.workspace.position_scale = w.number_or("position_scale", 1.0, 1e-3, 1e3);
    p.workspace.force_scale = w.number_or("force_scale", 1.0, 1e-3, 1e3);
  }
  p.validate();
  return p;
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
