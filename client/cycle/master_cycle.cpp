#include "client/cycle/master_cycle.hpp"

#include <cstdio>
#include <string>

namespace teleop::master {

double min_jerk(double t_s, double duration_s) {
  if (duration_s <= 0.0 || t_s >= duration_s) return 1.0;
  if (t_s <= 0.0) return 0.0;
  const double u = t_s / duration_s;
  return u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
}

MasterCycle::MasterCycle(const MasterCycleConfig& cfg, HapticDevice& device, SlaveLink& link)
    : cfg_(cfg),
      device_(device),
      link_(link),
      controller_(make_controller(cfg.controller.scheme)),
      forward_(cfg.forward),
      backward_(cfg.backward),
      metrics_(cfg.verdict) {
  if (!(cfg.dt_s > 0.0 && cfg.dt_s <= 0.1)) {
    throw config::ConfigError("master cycle: dt_s = " + std::to_string(cfg.dt_s) +
                              " is out of the allowed range (0, 0.1]");
  }
}

void MasterCycle::prepare(double now_s) {
  if (device_.state() == DeviceLifecycle::kUnconfigured) device_.configure();
  device_.activate();
  controller_->configure(cfg_.controller, device_.spec());
  if (cfg_.session_id != 0) controller_->set_session_id(cfg_.session_id);
  safety_.configure(cfg_.safety, device_.spec());
  metrics_.reset();
  forward_.reset();
  backward_.reset();
  newest_ = SlaveSample{};
  sample_ = MetricsSample{};
  command_ = SlaveCommand{};
  force_n_.setZero();
  controller_force_n_.setZero();
  origin_s_ = now_s;
  last_rx_s_ = -1.0;
  seq_ = 0;
  sample_arrived_ = false;
  homing_cycle_ = false;
  reading_ = device_.read();
}

void MasterCycle::start(double now_s) {
  prepare(now_s);
  homing_ = false;
  controller_->activate(reading_);
  session_start_s_ = now_s;
}

void MasterCycle::start_homing(double now_s, const Eigen::Vector3d& slave_tip_m, double duration_s,
                               double tolerance_m, double timeout_s) {
  if (duration_s <= 0.0) {
    start(now_s);
    return;
  }
  prepare(now_s);
  homing_ = true;
  session_start_s_ = -1.0;
  homing_start_s_ = now_s;
  homing_duration_s_ = duration_s;
  homing_tolerance_m_ = tolerance_m;
  homing_timeout_s_ = timeout_s;
  homing_from_m_ = slave_tip_m;
  slave_tip_m_ = slave_tip_m;
  homing_target_m_ = slave_tip_m;
  homing_goal_m_ = cfg_.controller.workspace.to_slave_position(reading_.position_m);
}

void MasterCycle::end_homing(double now_s) {
  homing_ = false;
  session_start_s_ = now_s;
  controller_->activate(device_.read());
  last_rx_s_ = now_s;
}

void MasterCycle::step(double now_s) {
  const double dt = cfg_.dt_s;
  // slave side of the link -> backward channel -> the controller's newest sample
  sample_arrived_ = false;
  SlaveSample arrived;
  double arrived_at_s = now_s;
  if (link_.receive(now_s, arrived, arrived_at_s)) backward_.push(arrived, arrived_at_s);
  if (backward_.pop_newest(now_s, newest_)) {
    last_rx_s_ = now_s;
    slave_tip_m_ = newest_.position_m;
    sample_arrived_ = true;
  }

  reading_ = device_.read();
  if (homing_) {
    // the slave follows the path; the operator feels nothing
    const double th = now_s - homing_start_s_;
    homing_target_m_ =
        homing_from_m_ + min_jerk(th, homing_duration_s_) * (homing_goal_m_ - homing_from_m_);
    command_ = SlaveCommand{};
    command_.position_m = homing_target_m_;
    command_.orientation = Eigen::Quaterniond::Identity();
    command_.position_gain_n_per_m = cfg_.controller.slave_stiffness_n_per_m;
    command_.enabled = true;
    force_n_.setZero();
    controller_force_n_.setZero();
    device_.write(force_n_, Eigen::Vector3d::Zero());
    sample_.master_position_m = homing_target_m_;
    sample_.device_force_n.setZero();
    sample_.safety_scale = safety_.scale();
    if (th >= homing_duration_s_ && ((slave_tip_m_ - homing_goal_m_).norm() < homing_tolerance_m_ ||
                                     th > homing_duration_s_ + homing_timeout_s_)) {
      end_homing(now_s);
    }
    homing_cycle_ = true;
  } else {
    homing_cycle_ = false;
    const ControlOutput out = controller_->update(reading_, newest_, dt);
    controller_force_n_ = out.force_n;
    force_n_ = cfg_.safety_enabled ? safety_.filter(now_s, dt, out.force_n, last_rx_s_,
                                                    controller_->force_limit_n(), metrics_)
                                   : out.force_n;
    device_.write(force_n_, out.torque_nm);
    command_ = out.command;
    sample_.master_position_m = command_.position_m;  // the device mapped to the slave frame
  }

  // command -> forward channel -> link
  command_.seq = ++seq_;
  command_.send_time_s = now_s;
  forward_.push(command_, now_s);
  SlaveCommand due;
  if (cfg_.delivery == ForwardDelivery::kNewestDue) {
    if (forward_.pop_newest(now_s, due)) link_.send(due);
  } else {
    while (forward_.pop(now_s, due)) link_.send(due);
  }
}

void MasterCycle::finish(double now_s, const SlaveSample* slave_truth) {
  const SlaveSample& slave = slave_truth ? *slave_truth : newest_;
  const WorkspaceMap& w = cfg_.controller.workspace;
  sample_.time_s = now_s - origin_s_;
  sample_.dt_s = cfg_.dt_s;
  sample_.slave_position_m = slave.position_m;
  sample_.have_slave = slave_truth ? true : newest_.valid;
  sample_.master_velocity_mps = reading_.linear_velocity_mps;
  sample_.device_force_n = force_n_;
  // the force the scheme means to render: beta R^T f_e (times K_f for force reflection)
  sample_.environment_force_n =
      controller_->environment_force_gain() * w.to_master_force(slave.contact_force_n);
  sample_.force_limit_n = controller_->force_limit_n();
  sample_.in_contact = slave.in_contact;
  sample_.link_ok = !safety_.link_lost();
  sample_.safety_scale = cfg_.safety_enabled ? safety_.scale() : 1.0;
  if (homing_cycle_) return;  // homing is not part of the session's figures

  metrics_.update(sample_);
  const ChannelCounters& fw = forward_.counters();
  const ChannelCounters& bw = backward_.counters();
  metrics_.set_losses(fw.pushed, fw.lost_random + fw.lost_burst + fw.lost_overflow + fw.lost_window,
                      bw.pushed,
                      bw.lost_random + bw.lost_burst + bw.lost_overflow + bw.lost_window);
  // a cut by the safety layer (saturation, energy) makes the run unstable even if the
  // windows evaluated so far did not show it
  if (cfg_.safety_enabled && safety_.cut()) {
    metrics_.mark_unstable(safety_.cut_reason(), sample_.time_s);
  }
  device_.advance(cfg_.dt_s);
}

void MasterCycle::stop() {
  controller_->deactivate();
  device_.write(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  device_.deactivate();
}

std::string channel_json(const ChannelReport& r) {
  char buf[512];
  const auto& c = r.counters;
  std::snprintf(
      buf, sizeof(buf),
      "{\"pushed\":%llu,\"delivered\":%llu,\"lost_random\":%llu,\"lost_burst\":%llu,"
      "\"lost_overflow\":%llu,\"lost_window\":%llu,\"stale\":%llu,\"loss_fraction\":%.6g,"
      "\"delay_mean_ms\":%.6g,\"delay_std_ms\":%.6g,\"delay_p50_ms\":%.6g,"
      "\"delay_p99_ms\":%.6g,\"delay_max_ms\":%.6g}",
      static_cast<unsigned long long>(c.pushed), static_cast<unsigned long long>(c.delivered),
      static_cast<unsigned long long>(c.lost_random), static_cast<unsigned long long>(c.lost_burst),
      static_cast<unsigned long long>(c.lost_overflow),
      static_cast<unsigned long long>(c.lost_window), static_cast<unsigned long long>(c.stale),
      r.loss_fraction, r.delay_mean_ms, r.delay_std_ms, r.delay_p50_ms, r.delay_p99_ms,
      r.delay_max_ms);
  return buf;
}

}  // namespace teleop::master
