#include "client/control/bilateral_controller.hpp"

#include <algorithm>
#include <cmath>

namespace teleop::master {

using config::ConfigError;

namespace {
void check(const char* field, double v, double lo, double hi) {
  if (!(v >= lo && v <= hi)) {
    throw ConfigError(std::string("controller: ") + field + " = " + std::to_string(v) +
                      " is out of the allowed range " + config::range_text(lo, hi));
  }
}
}  // namespace

void ControllerParams::validate() const {
  if (scheme != "position-position" && scheme != "force-position") {
    throw ConfigError("controller: scheme '" + scheme +
                      "' is unknown (allowed: position-position, force-position)");
  }
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
                            "max_force_n", "send_velocity"});
  p.scheme = node.choice_or("scheme", p.scheme, {"position-position", "force-position"});
  p.slave_stiffness_n_per_m =
      node.number_or("slave_stiffness_n_per_m", p.slave_stiffness_n_per_m, 0.0, 1e6);
  p.master_stiffness_n_per_m =
      node.number_or("master_stiffness_n_per_m", p.master_stiffness_n_per_m, 0.0, 1e6);
  p.master_damping_ns_per_m =
      node.number_or("master_damping_ns_per_m", p.master_damping_ns_per_m, 0.0, 1e4);
  p.force_gain = node.number_or("force_gain", p.force_gain, 0.0, 100.0);
  p.max_force_n = node.number_or("max_force_n", p.max_force_n, 0.0, 1e4);
  p.send_velocity = node.boolean_or("send_velocity", p.send_velocity);
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
}

void BilateralController::activate(const DeviceReading& /*master*/) {
  seq_ = 0;
  active_ = true;
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
  c.master_force_n = w.to_slave_force(out.force_n);
  return out;
}

void PositionPositionController::compute(const DeviceReading& master, const SlaveSample& slave,
                                         double /*dt_s*/, ControlOutput& out) {
  // F_m = K_pm (x_s' - x_m) - B_m v_m; with no slave sample yet, damping only
  Eigen::Vector3d f = -b_m_ * master.linear_velocity_mps;
  if (slave.valid) {
    const Eigen::Vector3d xs_master = params_.workspace.to_master_position(slave.position_m);
    f += k_pm_ * (xs_master - master.position_m);
  }
  out.force_n = f;
}

void ForcePositionController::compute(const DeviceReading& master, const SlaveSample& slave,
                                      double /*dt_s*/, ControlOutput& out) {
  // F_m = K_f beta R^T f_e - B_m v_m
  Eigen::Vector3d f = -b_m_ * master.linear_velocity_mps;
  if (slave.valid) {
    f += params_.force_gain * params_.workspace.to_master_force(slave.contact_force_n);
  }
  out.force_n = f;
}

std::unique_ptr<BilateralController> make_controller(const std::string& scheme) {
  if (scheme == "position-position") return std::make_unique<PositionPositionController>();
  if (scheme == "force-position") return std::make_unique<ForcePositionController>();
  throw ConfigError("controller: scheme '" + scheme +
                    "' is unknown (allowed: position-position, force-position)");
}

std::vector<std::string> controller_names() { return {"position-position", "force-position"}; }

}  // namespace teleop::master
