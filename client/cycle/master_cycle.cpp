#include "client/cycle/master_cycle.hpp"

#include "common/util/json.hpp"

#include <algorithm>
#include <cstdio>
#include <string>

namespace teleop::master {

const char* to_string(RehomeReason r) {
  switch (r) {
    case RehomeReason::kLinkBack:
      return "link back after a loss";
    case RehomeReason::kSlaveRestart:
      return "the slave restarted";
    case RehomeReason::kTakeover:
      return "took the slave over";
    case RehomeReason::kDriverBack:
      return "the device's readings came back";
  }
  return "?";
}

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
      sent_position_m_(kSentRing, Eigen::Vector3d::Zero()),
      sent_force_n_(kSentRing, Eigen::Vector3d::Zero()),
      metrics_(cfg.verdict) {
  if (!(cfg.dt_s > 0.0 && cfg.dt_s <= 0.1)) {
    throw config::ConfigError("master cycle: dt_s = " + std::to_string(cfg.dt_s) +
                              " is out of the allowed range (0, 0.1]");
  }
  if (!(cfg.driver_timeout_s > 0.0 && cfg.driver_timeout_s <= 10.0)) {
    throw config::ConfigError(
        "master cycle: driver_timeout_s = " + std::to_string(cfg.driver_timeout_s) +
        " s is out of the allowed range (0, 10]");
  }
}

void MasterCycle::prepare(double now_s) {
  if (device_.state() == DeviceLifecycle::kUnconfigured) device_.configure();
  device_.activate();
  controller_->configure(cfg_.controller, device_.spec());
  if (cfg_.session_id != 0) controller_->set_session_id(cfg_.session_id);
  safety_.configure(cfg_.safety, device_.spec());
  tuning_limits_ =
      master::tuning_limits(cfg_.controller, device_.spec(),
                            std::min(cfg_.forward.capacity, cfg_.backward.capacity), cfg_.dt_s);
  TuningValues in_force;
  in_force.master_stiffness_n_per_m = controller_->master_stiffness_n_per_m();
  in_force.master_damping_ns_per_m = controller_->master_damping_ns_per_m();
  in_force.force_gain = controller_->params().force_gain;
  in_force.slave_stiffness_n_per_m = controller_->params().slave_stiffness_n_per_m;
  in_force.forward_delay_s = cfg_.forward.delay_s;
  in_force.backward_delay_s = cfg_.backward.delay_s;
  tuning_.reset(in_force);
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
  cycles_ = 0;
  sample_arrived_ = false;
  homing_cycle_ = false;
  held_ = false;
  track_goal_ = false;
  link_was_lost_ = false;
  epoch_seen_ = 0;
  have_epoch_ = false;
  rehomes_ = 0;
  workspace_violations_ = 0;
  outside_workspace_ = false;
  std::fill(std::begin(rehomes_by_), std::end(rehomes_by_), 0);
  invalid_since_s_ = -1.0;
  driver_silent_ = false;
  driver_silences_ = 0;
  driver_silent_total_s_ = 0.0;
  next_session_id_ = cfg_.session_id;
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
  // the goal follows the device: a device held still (the simulated and replayed ones do not
  // move while homing) gives the fixed path of the first versions
  track_goal_ = true;
}

void MasterCycle::rehome(double now_s, RehomeReason why) {
  ++rehomes_;
  ++rehomes_by_[static_cast<std::size_t>(why)];
  controller_->deactivate();
  link_was_lost_ = false;
  homing_ = true;
  track_goal_ = true;
  homing_start_s_ = now_s;
  homing_from_m_ = slave_tip_m_;
  homing_target_m_ = slave_tip_m_;
  homing_goal_m_ = cfg_.controller.workspace.to_slave_position(reading_.position_m);
  const double distance_m = (homing_goal_m_ - homing_from_m_).norm();
  homing_duration_s_ =
      std::clamp(distance_m / std::max(cfg_.rehome_speed_mps, 1e-6), cfg_.rehome_min_s,
                 std::max(cfg_.rehome_min_s, cfg_.rehome_max_s));
  char msg[sizeof(sim::SimEvent::message)];
  std::snprintf(msg, sizeof(msg), "re-homing (%s): slave %.3f m from the master, %.2f s path",
                to_string(why), distance_m, homing_duration_s_);
  safety_.events().push(sim::EventKind::kModeChange, sim::Severity::kWarning, now_s, distance_m,
                        msg);
}

void MasterCycle::end_homing(double now_s) {
  homing_ = false;
  const bool first = session_start_s_ < 0.0;
  if (first) {
    session_start_s_ = now_s;
  } else {
    // a new passivity session: the slave restarts its port state with it
    if (next_session_id_ != 0) {
      next_session_id_ += 2;
      controller_->set_session_id(next_session_id_);
    }
  }
  // the first force fades in too: the device may have moved the slave into contact while it
  // homed (a hand on a real device does), and the contact force must not start as a step
  safety_.fade_in();
  controller_->activate(device_.read());
  last_rx_s_ = now_s;
}

void MasterCycle::check_rehome(double now_s) {
  // the epoch is checked on the sample that came through the backward channel, so the path
  // starts where the restarted slave is
  const bool restarted = sample_arrived_ && have_epoch_ && newest_.slave_epoch != epoch_seen_;
  if (sample_arrived_) {
    epoch_seen_ = newest_.slave_epoch;
    have_epoch_ = true;
  }
  if (held_) return;
  if (restarted) {
    rehome(now_s, RehomeReason::kSlaveRestart);
  } else if (link_was_lost_ && sample_arrived_ && !homing_) {
    rehome(now_s, RehomeReason::kLinkBack);
  }
}

void MasterCycle::render_nothing(const Eigen::Vector3d& target_m, bool enabled) {
  command_ = SlaveCommand{};
  command_.position_m = target_m;
  command_.orientation = Eigen::Quaterniond::Identity();
  command_.position_gain_n_per_m = cfg_.controller.slave_stiffness_n_per_m;
  command_.enabled = enabled;
  force_n_ = cfg_.safety_enabled ? safety_.hold_zero(cfg_.dt_s) : Eigen::Vector3d::Zero();
  controller_force_n_.setZero();
  device_.write(force_n_, Eigen::Vector3d::Zero());
  sample_.master_position_m = target_m;
  sample_.device_force_n = force_n_;
  sample_.safety_scale = safety_.scale();
  homing_cycle_ = true;
}

void MasterCycle::homing_step(double now_s) {
  // the slave follows the path; the operator feels nothing
  const double th = now_s - homing_start_s_;
  if (track_goal_) {
    homing_goal_m_ = cfg_.controller.workspace.to_slave_position(reading_.position_m);
  }
  homing_target_m_ =
      homing_from_m_ + min_jerk(th, homing_duration_s_) * (homing_goal_m_ - homing_from_m_);
  render_nothing(homing_target_m_, true);
  if (th >= homing_duration_s_ && ((slave_tip_m_ - homing_goal_m_).norm() < homing_tolerance_m_ ||
                                   th > homing_duration_s_ + homing_timeout_s_)) {
    end_homing(now_s);
  }
}

void MasterCycle::check_workspace(double now_s) {
  if (!reading_.valid) return;
  const DeviceSpec& s = device_.spec();
  const Eigen::Vector3d lo = s.workspace_min_m.array() - kWorkspaceTolerance_m;
  const Eigen::Vector3d hi = s.workspace_max_m.array() + kWorkspaceTolerance_m;
  const bool outside = !reading_.position_m.allFinite() ||
                       (reading_.position_m.array() < lo.array()).any() ||
                       (reading_.position_m.array() > hi.array()).any();
  if (outside) {
    reading_.valid = false;  // a driver fault or a miscalibration: render nothing, hold
    ++workspace_violations_;
    if (!outside_workspace_) {
      safety_.events().push(sim::EventKind::kLimit, sim::Severity::kWarning, now_s - origin_s_,
                            reading_.position_m.norm(),
                            "the device reads a position outside the workspace it declared: "
                            "no force, the slave holds");
    }
  }
  outside_workspace_ = outside;
}

void MasterCycle::check_driver(double now_s) {
  if (reading_.valid) {
    if (driver_silent_) {
      const double silent_s = now_s - invalid_since_s_;
      driver_silent_total_s_ += silent_s;
      driver_silent_ = false;
      char msg[sizeof(sim::SimEvent::message)];
      std::snprintf(msg, sizeof(msg), "device readings back after %.3f s of silence", silent_s);
      safety_.events().push(sim::EventKind::kWatchdog, sim::Severity::kWarning, now_s - origin_s_,
                            silent_s, msg);
      if (!held_) rehome(now_s, RehomeReason::kDriverBack);
    }
    invalid_since_s_ = -1.0;
    return;
  }
  if (invalid_since_s_ < 0.0) invalid_since_s_ = now_s;
  if (driver_silent_ || now_s - invalid_since_s_ <= cfg_.driver_timeout_s) return;
  driver_silent_ = true;
  ++driver_silences_;
  char msg[sizeof(sim::SimEvent::message)];
  std::snprintf(msg, sizeof(msg),
                "device silent: no valid reading for %.0f ms (timeout %.0f ms): the slave holds, "
                "the force fades to zero at %.0f N/s",
                (now_s - invalid_since_s_) * 1e3, cfg_.driver_timeout_s * 1e3,
                device_.spec().max_force_rate_n_per_s);
  safety_.events().push(sim::EventKind::kWatchdog, sim::Severity::kWarning, now_s - origin_s_,
                        now_s - invalid_since_s_, msg);
}

std::string MasterCycle::tune(const TuningRequestData& request, double now_s) {
  std::string problem = check_tuning(request, tuning_limits_, cfg_.controller.scheme);
  if (!problem.empty()) {
    ++tunings_rejected_;
    return problem;
  }
  ++tunings_accepted_;
  tuning_.start(request, now_s, tuning_limits_.min_ramp_s);
  return {};
}

void MasterCycle::step(double now_s) {
  const double dt = cfg_.dt_s;
  // live tuning: gains and injected delays move along their ramps
  if (tuning_.advance(now_s)) {
    const TuningValues& v = tuning_.current();
    controller_->retune(v.master_stiffness_n_per_m, v.master_damping_ns_per_m, v.force_gain,
                        v.slave_stiffness_n_per_m);
    forward_.set_delay_s(v.forward_delay_s);
    backward_.set_delay_s(v.backward_delay_s);
  }
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
  check_workspace(now_s);
  check_driver(now_s);
  check_rehome(now_s);
  if (held_ || driver_silent_) {
    // refused, closing or no device: ask nothing of the slave
    render_nothing(slave_tip_m_, false);
  } else if (homing_) {
    homing_step(now_s);
  } else {
    homing_cycle_ = false;
    const ControlOutput out = controller_->update(reading_, newest_, dt);
    controller_force_n_ = out.force_n;
    force_n_ = cfg_.safety_enabled ? safety_.filter(now_s, dt, out.force_n, last_rx_s_,
                                                    controller_->force_limit_n(), metrics_)
                                   : out.force_n;
    if (cfg_.rehome_on_link_back && cfg_.safety_enabled && safety_.link_lost()) {
      link_was_lost_ = true;
    }
    device_.write(force_n_, out.torque_nm);
    command_ = out.command;
    sample_.master_position_m = command_.position_m;  // the device mapped to the slave frame
  }

  // command -> forward channel -> link (every command_every cycles)
  if (cycles_++ % std::max<std::uint32_t>(1, cfg_.command_every) == 0) {
    command_.seq = ++seq_;
    command_.send_time_s = now_s;
    forward_.push(command_, now_s);
    // what the master was and felt when it sent this command (the transparency figures)
    sent_position_m_[seq_ % kSentRing] = sample_.master_position_m;
    sent_force_n_[seq_ % kSentRing] = cfg_.controller.workspace.to_slave_force(force_n_);
  }
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
  // transparency: depths and forces along the contact normal, in the slave's units; the
  // master's side is taken at the time of the command the slave's sample echoes (over a
  // network the newest sample that arrived, in-process the slave's ground truth)
  Eigen::Vector3d x_m = sample_.master_position_m, f_m = w.to_slave_force(force_n_);
  sample_.transparency_valid = slave_truth != nullptr;
  if ((slave_truth || sample_arrived_) && slave.command_seq >= 1 && slave.command_seq <= seq_ &&
      seq_ - slave.command_seq < kSentRing) {
    const std::size_t k = slave.command_seq % kSentRing;
    x_m = sent_position_m_[k];
    f_m = sent_force_n_[k];
    sample_.transparency_valid = true;
  }
  sample_.aligned_force_n = w.to_master_force(f_m).norm();
  const double fe = slave.contact_force_n.norm();
  sample_.contact_force_n = slave.in_contact ? fe : 0.0;
  sample_.slave_depth_m = sample_.master_depth_m = sample_.felt_force_n = 0.0;
  if (slave.in_contact && fe > 1e-9) {
    const Eigen::Vector3d n = slave.contact_force_n / fe;  // out of the object
    sample_.slave_depth_m = slave.deformation_m > 0.0 ? slave.deformation_m : slave.penetration_m;
    sample_.master_depth_m = sample_.slave_depth_m + n.dot(slave.position_m - x_m);
    sample_.felt_force_n = f_m.dot(n);
  }
  sample_.continuous_force_n = device_.spec().max_continuous_force_n;
  // homing, holding and cycles without a valid device reading are not part of the figures
  if (homing_cycle_) return;
  if (!reading_.valid) {
    device_.advance(cfg_.dt_s);
    return;
  }

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

OrderedJson channel_fields(const ChannelReport& r) {
  const auto& c = r.counters;
  OrderedJson o;
  o["pushed"] = c.pushed;
  o["delivered"] = c.delivered;
  o["lost_random"] = c.lost_random;
  o["lost_burst"] = c.lost_burst;
  o["lost_overflow"] = c.lost_overflow;
  o["lost_window"] = c.lost_window;
  o["stale"] = c.stale;
  o["loss_fraction"] = json_number(r.loss_fraction);
  o["delay_mean_ms"] = json_number(r.delay_mean_ms);
  o["delay_std_ms"] = json_number(r.delay_std_ms);
  o["delay_p50_ms"] = json_number(r.delay_p50_ms);
  o["delay_p99_ms"] = json_number(r.delay_p99_ms);
  o["delay_max_ms"] = json_number(r.delay_max_ms);
  return o;
}

std::string channel_json(const ChannelReport& r) { return json_compact(channel_fields(r)); }

}  // namespace teleop::master
