#include "client/control/safety.hpp"

#include <algorithm>
#include <cmath>

namespace teleop::master {

using teleop::sim::EventKind;
using teleop::sim::Severity;

void SafetyLayer::configure(const SafetyParams& params, const DeviceSpec& spec) {
  p_ = params;
  spec_ = spec;
  state_ = SafetyState::kNormal;
  scale_ = 1.0;
  link_lost_ = false;
  thermal_limited_ = false;
  sat_time_s_ = 0.0;
  f_avg_n_ = 0.0;
  max_out_ = 0.0;
  cut_time_s_ = -1.0;
  cut_reason_ = "";
  faults_ = 0;
  rate_limited_ = 0;
  max_step_n_ = 0.0;
  last_out_.setZero();
  events_.clear();
}

Eigen::Vector3d SafetyLayer::limit_rate(const Eigen::Vector3d& target, double dt_s) {
  Eigen::Vector3d f = target;
  const Eigen::Vector3d delta = target - last_out_;
  const double d = delta.norm();
  const double max_d = spec_.max_force_rate_n_per_s > 0.0 ? spec_.max_force_rate_n_per_s * dt_s : d;
  if (d > max_d) {
    // both ends lie within the peak force, so every point between them does too
    f = last_out_ + delta * (max_d / d);
    ++rate_limited_;
  }
  max_step_n_ = std::max(max_step_n_, (f - last_out_).norm());
  last_out_ = f;
  max_out_ = std::max(max_out_, f.norm());
  return f;
}

Eigen::Vector3d SafetyLayer::hold_zero(double dt_s) {
  return limit_rate(Eigen::Vector3d::Zero(), dt_s);
}

void SafetyLayer::rearm() {
  state_ = link_lost_ ? SafetyState::kLinkLost : SafetyState::kNormal;
  scale_ = 0.0;  // fade back in
  sat_time_s_ = 0.0;
  cut_reason_ = "";
  cut_time_s_ = -1.0;
}

void SafetyLayer::do_cut(double now_s, const char* reason) {
  if (state_ == SafetyState::kCut) return;
  state_ = SafetyState::kCut;
  cut_reason_ = reason;
  cut_time_s_ = now_s;
  events_.push(EventKind::kSafety, Severity::kError, now_s, scale_, reason);
}

Eigen::Vector3d SafetyLayer::filter(double now_s, double dt_s, const Eigen::Vector3d& force_n,
                                    double last_slave_rx_s, double limit_n,
                                    const SessionMetrics& metrics) {
  Eigen::Vector3d f = force_n;
  if (!f.allFinite()) {
    ++faults_;
    events_.push(EventKind::kFault, Severity::kError, now_s, 0.0, "non-finite device force");
    f.setZero();
  }

  // link watchdog
  const bool lost = last_slave_rx_s < 0.0 ? now_s > p_.link_timeout_s
                                          : now_s - last_slave_rx_s > p_.link_timeout_s;
  if (lost != link_lost_) {
    link_lost_ = lost;
    events_.push(EventKind::kWatchdog, lost ? Severity::kWarning : Severity::kInfo, now_s,
                 now_s - last_slave_rx_s, lost ? "link lost: fading force out" : "link back");
  }

  // cut conditions
  const double fn = f.norm();
  sat_time_s_ = fn >= 0.99 * limit_n ? sat_time_s_ + dt_s : 0.0;
  if (state_ != SafetyState::kCut) {
    if (p_.cut_on_unstable && metrics.verdict() == Verdict::kUnstable) {
      do_cut(now_s, "unstable");
    } else if (sat_time_s_ > p_.saturation_limit_s) {
      do_cut(now_s, "force at the limit too long");
    } else if (p_.cut_on_energy && metrics.energy_growing()) {
      do_cut(now_s, "energy growing");
    } else {
      state_ = link_lost_ ? SafetyState::kLinkLost : SafetyState::kNormal;
    }
  }

  // ramp the scale towards its target
  double target = 1.0;
  double fade = p_.link_fade_s;
  if (state_ == SafetyState::kCut) {
    target = 0.0;
    fade = p_.cut_fade_s;
  } else if (state_ == SafetyState::kLinkLost) {
    target = 0.0;
  }
  const double step = fade > 0.0 ? dt_s / fade : 1.0;
  scale_ = target < scale_ ? std::max(target, scale_ - step) : std::min(target, scale_ + step);
  f *= scale_;

  // thermal model of the actuators: clamp to the continuous force while hot
  if (p_.thermal_limit && spec_.max_continuous_force_n > 0.0) {
    const double a = std::min(1.0, dt_s / std::max(p_.continuous_tau_s, 1e-9));
    f_avg_n_ += a * (f.norm() - f_avg_n_);
    if (!thermal_limited_ && f_avg_n_ > spec_.max_continuous_force_n) {
      thermal_limited_ = true;
      events_.push(EventKind::kLimit, Severity::kWarning, now_s, f_avg_n_,
                   "continuous force limit: clamping");
    } else if (thermal_limited_ && f_avg_n_ < 0.9 * spec_.max_continuous_force_n) {
      thermal_limited_ = false;
    }
    if (thermal_limited_) f = saturate_norm(f, spec_.max_continuous_force_n);
  }
  f = saturate_norm(f, std::min(limit_n, spec_.max_force_n));
  return limit_rate(f, dt_s);
}

}  // namespace teleop::master
