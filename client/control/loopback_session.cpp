#include "client/control/loopback_session.hpp"

#include <cstdio>

namespace teleop::master {

LoopbackSession::LoopbackSession(const LoopbackConfig& cfg, HapticDevice& device,
                                 SlaveSimulator& slave)
    : cfg_(cfg),
      device_(device),
      slave_(slave),
      controller_(make_controller(cfg.controller.scheme)),
      forward_(cfg.forward),
      backward_(cfg.backward),
      metrics_(cfg.verdict) {
  if (!(cfg.dt_s > 0.0 && cfg.dt_s <= 0.1)) {
    throw config::ConfigError("loopback: dt_s = " + std::to_string(cfg.dt_s) +
                              " is out of the allowed range (0, 0.1]");
  }
}

void LoopbackSession::start() {
  if (device_.state() == DeviceLifecycle::kUnconfigured) device_.configure();
  device_.activate();
  controller_->configure(cfg_.controller, device_.spec());
  safety_.configure(cfg_.safety, device_.spec());
  metrics_.reset();
  forward_.reset();
  backward_.reset();
  const DeviceReading r = device_.read();
  controller_->activate(r);
  slave_.reset(cfg_.controller.workspace.to_slave_position(r.position_m));
  slave_cmd_ = SlaveCommand{};
  slave_cmd_.enabled = false;  // hold until the first command arrives
  slave_rx_ = SlaveSample{};
  last_rx_s_ = -1.0;
  t_s_ = 0.0;
  started_ = true;
}

bool LoopbackSession::step() {
  if (t_s_ >= cfg_.duration_s - 0.5 * cfg_.dt_s) return false;
  const double dt = cfg_.dt_s;
  const double now = t_s_;

  // master side
  const DeviceReading r = device_.read();
  if (backward_.pop_newest(now, slave_rx_)) last_rx_s_ = now;
  const ControlOutput out = controller_->update(r, slave_rx_, dt);
  controller_force_n_ = out.force_n;
  const Eigen::Vector3d f =
      cfg_.safety_enabled
          ? safety_.filter(now, dt, out.force_n, last_rx_s_, controller_->force_limit_n(), metrics_)
          : out.force_n;
  device_.write(f, out.torque_nm);
  forward_.push(out.command, now);

  // slave side
  forward_.pop_newest(now, slave_cmd_);
  slave_.step(slave_cmd_, dt);
  if (!backward_outage_) backward_.push(slave_.sample(), now);

  // metrics (ground truth of the slave, since both run here)
  const SlaveSample truth = slave_.sample();
  const WorkspaceMap& w = cfg_.controller.workspace;
  last_.time_s = now;
  last_.dt_s = dt;
  last_.master_position_m = w.to_slave_position(r.position_m);
  last_.slave_position_m = truth.position_m;
  last_.master_velocity_mps = r.linear_velocity_mps;
  last_.device_force_n = f;
  // the force the scheme means to render: beta R^T f_e (times K_f for force reflection)
  last_.environment_force_n =
      controller_->environment_force_gain() * w.to_master_force(truth.contact_force_n);
  last_.force_limit_n = controller_->force_limit_n();
  last_.in_contact = truth.in_contact;
  last_.have_slave = true;
  last_.link_ok = !safety_.link_lost();
  last_.safety_scale = cfg_.safety_enabled ? safety_.scale() : 1.0;
  metrics_.update(last_);
  {
    const ChannelCounters& fw = forward_.counters();
    const ChannelCounters& bw = backward_.counters();
    metrics_.set_losses(fw.pushed, fw.lost_random + fw.lost_burst + fw.lost_overflow, bw.pushed,
                        bw.lost_random + bw.lost_burst + bw.lost_overflow);
  }
  // a cut by the safety layer (saturation, energy) makes the run unstable even if the
  // windows evaluated so far did not show it
  if (cfg_.safety_enabled && safety_.cut()) metrics_.mark_unstable(safety_.cut_reason(), now);

  device_.advance(dt);
  t_s_ += dt;
  return true;
}

void LoopbackSession::run() {
  if (!started_) start();
  while (step()) {
  }
}

std::string channel_json(const ChannelReport& r) {
  char buf[512];
  const auto& c = r.counters;
  std::snprintf(
      buf, sizeof(buf),
      "{\"pushed\":%llu,\"delivered\":%llu,\"lost_random\":%llu,\"lost_burst\":%llu,"
      "\"lost_overflow\":%llu,\"stale\":%llu,\"loss_fraction\":%.6g,"
      "\"delay_mean_ms\":%.6g,\"delay_std_ms\":%.6g,\"delay_p50_ms\":%.6g,"
      "\"delay_p99_ms\":%.6g,\"delay_max_ms\":%.6g}",
      static_cast<unsigned long long>(c.pushed), static_cast<unsigned long long>(c.delivered),
      static_cast<unsigned long long>(c.lost_random), static_cast<unsigned long long>(c.lost_burst),
      static_cast<unsigned long long>(c.lost_overflow), static_cast<unsigned long long>(c.stale),
      r.loss_fraction, r.delay_mean_ms, r.delay_std_ms, r.delay_p50_ms, r.delay_p99_ms,
      r.delay_max_ms);
  return buf;
}

std::string LoopbackSession::summary_json() const {
  std::string s = "{\"scheme\":\"";
  s += controller_->name();
  s += "\",\"metrics\":" + metrics_.summary_json();
  s += ",\"forward\":" + channel_json(forward_.report());
  s += ",\"backward\":" + channel_json(backward_.report());
  s += ",\"safety\":{\"cut\":";
  s += safety_.cut() ? "true" : "false";
  s += ",\"reason\":\"";
  s += safety_.cut_reason();
  s += "\"}}";
  return s;
}

}  // namespace teleop::master
