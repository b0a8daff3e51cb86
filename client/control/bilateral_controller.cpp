#include "client/control/bilateral_controller.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <sstream>

#include "common/control/slave_port.hpp"

namespace teleop::master {

using config::ConfigError;

namespace {
std::string number_text(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}

void check(const char* field, double v, double lo, double hi) {
  if (!(v >= lo && v <= hi)) {
    throw ConfigError(std::string("controller: ") + field + " = " + number_text(v) +
                      " is out of the allowed range " + config::range_text(lo, hi));
  }
}

const std::vector<std::string>& scheme_names() {
  static const std::vector<std::string> names = {"position-position", "force-position",
                                                 "wave-variables", "tdpa", "model-mediated"};
  return names;
}

std::string joined_names() {
  std::string s;
  for (const auto& n : scheme_names()) s += (s.empty() ? "" : ", ") + n;
  return s;
}

/// Position-position: F_m = K_pm (x_s' - x_m) - B_m v_m (damping only before a slave sample).
Eigen::Vector3d position_position_force(const WorkspaceMap& w, double k_pm, double b_m,
                                        const DeviceReading& master, const SlaveSample& slave) {
  Eigen::Vector3d f = -b_m * master.linear_velocity_mps;
  if (slave.valid) f += k_pm * (w.to_master_position(slave.position_m) - master.position_m);
  return f;
}

/// Force-position: F_m = K_f beta R^T f_e - B_m v_m.
Eigen::Vector3d force_position_force(const WorkspaceMap& w, double k_f, double b_m,
                                     const DeviceReading& master, const SlaveSample& slave) {
  Eigen::Vector3d f = -b_m * master.linear_velocity_mps;
  if (slave.valid) f += k_f * w.to_master_force(slave.contact_force_n);
  return f;
}

/// `value` moved toward `target` by at most `step`.
double ramp_toward(double value, double target, double step) {
  return value < target ? std::min(target, value + step) : std::max(target, value - step);
}

std::atomic<std::uint32_t> g_session_counter{0};
}  // namespace

void ControllerParams::validate() const {
  if (std::find(scheme_names().begin(), scheme_names().end(), scheme) == scheme_names().end()) {
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
  p.scheme = node.choice_or("scheme", p.scheme, scheme_names());
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

void PositionPositionController::compute(const DeviceReading& master, const SlaveSample& slave,
                                         double /*dt_s*/, ControlOutput& out) {
  out.force_n = position_position_force(params_.workspace, k_pm_, b_m_, master, slave);
}

void ForcePositionController::on_activate(const DeviceReading& /*master*/) { damping_share_ = 0.0; }

void ForcePositionController::compute(const DeviceReading& master, const SlaveSample& slave,
                                      double dt_s, ControlOutput& out) {
  damping_share_ = ramp_toward(damping_share_, slave.valid && slave.in_contact ? 1.0 : 0.0,
                               dt_s / params_.contact_damping_ramp_s);
  out.force_n = force_position_force(params_.workspace, params_.force_gain, damping_share_ * b_m_,
                                     master, slave);
}

// --- model-mediated ---------------------------------------------------------------------------

void ModelMediatedController::on_activate(const DeviceReading& /*master*/) {
  status_ = ModelStatus{};
  status_.budget_j = params_.mmt_energy_burst_j;
}

void ModelMediatedController::blend_toward(const mmt::LocalModel& target, const Eigen::Vector3d& x,
                                           double dt_s) {
  mmt::LocalModel& cur = status_.rendered;
  // the device renders alpha beta k: keep it within the stiffness and damping it can render
  const WorkspaceMap& w = params_.workspace;
  const double ab = std::max(1e-9, w.position_scale * w.force_scale);
  mmt::LocalModel tgt = target;
  tgt.stiffness_n_per_m = std::min(tgt.stiffness_n_per_m, spec_.max_stiffness_n_per_m / ab);
  tgt.damping_ns_per_m = std::min(tgt.damping_ns_per_m, spec_.max_damping_ns_per_m / ab);
  mmt::LocalModel next = tgt;
  if (cur.valid && cur.normal.dot(tgt.normal) > std::cos(25.0 * M_PI / 180.0)) {
    // the same surface, moved or re-estimated: a first-order step toward the new model
    const double a = std::min(1.0, dt_s / params_.mmt_blend_s);
    next.normal = (cur.normal + a * (tgt.normal - cur.normal)).normalized();
    next.offset_m = cur.offset_m + a * (tgt.offset_m - cur.offset_m);
    next.stiffness_n_per_m =
        cur.stiffness_n_per_m + a * (tgt.stiffness_n_per_m - cur.stiffness_n_per_m);
    next.damping_ns_per_m =
        cur.damping_ns_per_m + a * (tgt.damping_ns_per_m - cur.damping_ns_per_m);
  }
  // energy the update would add where the master is: within the budget, else the surface
  // moves out so that it adds exactly the budget
  const double before_j = cur.valid ? cur.energy_j(x) : 0.0;
  double added_j = next.energy_j(x) - before_j;
  if (added_j > status_.budget_j) {
    const double allowed_j = before_j + status_.budget_j;
    next.offset_m = next.normal.dot(x) + std::sqrt(2.0 * allowed_j / next.stiffness_n_per_m);
    added_j = status_.budget_j;
    ++status_.limited_updates;
  }
  if (added_j > 0.0) {
    status_.budget_j -= added_j;
    status_.injected_j += added_j;
  }
  cur = next;
}

void ModelMediatedController::compute(const DeviceReading& master, const SlaveSample& slave,
                                      double dt_s, ControlOutput& out) {
  const WorkspaceMap& w = params_.workspace;
  const Eigen::Vector3d x = out.command.position_m;  // the master in the slave frame
  const Eigen::Vector3d v = w.to_slave_velocity(master.linear_velocity_mps);
  status_.budget_j =
      std::min(params_.mmt_energy_burst_j, status_.budget_j + params_.mmt_energy_rate_w * dt_s);
  mmt::LocalModel& cur = status_.rendered;
  if (slave.valid && slave.model.valid && slave.model.stiffness_n_per_m > 0.0) {
    ++status_.models_received;
    blend_toward(slave.model, x, dt_s);
  } else if (cur.valid) {
    // nothing near the slave any more: the model softens away (its energy only falls)
    cur.stiffness_n_per_m *= 1.0 - std::min(1.0, dt_s / params_.mmt_blend_s);
    cur.damping_ns_per_m *= 1.0 - std::min(1.0, dt_s / params_.mmt_blend_s);
    if (cur.stiffness_n_per_m < 1e-3) cur.valid = false;
  }
  const Eigen::Vector3d f_model = cur.force_n(x, v);
  status_.damping_share =
      ramp_toward(status_.damping_share, f_model.squaredNorm() > 0.0 ? 1.0 : 0.0,
                  dt_s / params_.contact_damping_ramp_s);
  out.force_n =
      w.to_master_force(f_model) - status_.damping_share * b_m_ * master.linear_velocity_mps;
}

// --- wave variables -------------------------------------------------------------------------

void WaveVariablesController::on_configure() {
  const WorkspaceMap& w = params_.workspace;
  const double derived = params_.slave_stiffness_n_per_m * params_.wave_time_constant_s;
  const double wanted =
      params_.wave_impedance_ns_per_m > 0.0 ? params_.wave_impedance_ns_per_m : derived;
  // the device renders the damping alpha beta b in free motion: keep it within the spec
  const double b_max = spec_.max_damping_ns_per_m / (w.position_scale * w.force_scale);
  b_ = std::min(wanted, b_max);
  if (!(b_ >= passivity::kMinWaveImpedance)) {
    throw ConfigError(
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
  if (have) v_energy_rx_ = slave.wave_v_energy_j;
  port_.update(c.position_m, xdot, slave.wave_v_integral, slave.wave_v_energy_j, have, dt_s);
  // the operator pushes F_m into the channel; the device renders -F_m (+ local damping)
  out.force_n = -w.to_master_force(port_.force_n()) - b_m_ * master.linear_velocity_mps;
  c.passivity_session = session_;
  c.wave_impedance_ns_per_m = b_;
  c.wave_matched = params_.wave_matched;
  c.wave_u = port_.u();
  c.wave_u_integral = port_.sent().integral;
  c.wave_u_energy_j = port_.sent().energy_j;
}

BilateralController::PassivityStatus WaveVariablesController::passivity_status() const {
  PassivityStatus s;
  // backward energy received but not (yet) used: what the receiver holds back, >= 0
  s.observer_j = (v_energy_rx_ - port_.received().used_energy_j()).sum();
  return s;
}

// --- time-domain passivity ------------------------------------------------------------------

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
  wanted_n_ = force_position_ ? force_position_force(w, params_.force_gain, b_m_, master, slave)
                              : position_position_force(w, k_pm_, b_m_, master, slave);
  // energies travel in the slave frame: P_slave = (alpha / beta) P_master
  const double to_master = w.force_scale / w.position_scale;
  if (slave.valid && slave.passivity_session == session_) {
    remote_in_j_ = slave.tdpa_energy_in_j * to_master;
    remote_out_j_ = slave.tdpa_energy_out_j * to_master;
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
  out.command.tdpa_energy_in_j = pc_.energy().in_j * (w.position_scale / w.force_scale);
}

BilateralController::PassivityStatus TimeDomainPassivityController::passivity_status() const {
  PassivityStatus s;
  s.observer_j = remote_in_j_ - pc_.energy().out_j;
  s.dissipated_j = pc_.energy().dissipated_j;
  s.alpha_ns_per_m = pc_.last_alpha();
  return s;
}

std::unique_ptr<BilateralController> make_controller(const std::string& scheme) {
  if (scheme == "position-position") return std::make_unique<PositionPositionController>();
  if (scheme == "force-position") return std::make_unique<ForcePositionController>();
  if (scheme == "wave-variables") return std::make_unique<WaveVariablesController>();
  if (scheme == "tdpa") return std::make_unique<TimeDomainPassivityController>();
  if (scheme == "model-mediated") return std::make_unique<ModelMediatedController>();
  throw ConfigError("controller: scheme '" + scheme + "' is unknown (allowed: " + joined_names() +
                    ")");
}

std::vector<std::string> controller_names() { return scheme_names(); }

}  // namespace teleop::master
