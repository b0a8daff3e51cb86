#include "client/node/experiment_publisher.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace teleop::master {

namespace {

const char* jitter_dist_name(const DelayConfig& c) {
  return c.jitter_dist == JitterDist::kNormal ? "normal" : "uniform";
}

/// The q-quantile of the first n values (reorders them). n > 0.
double quantile(double* v, std::size_t n, double q) {
  const std::size_t k =
      std::min(n - 1, static_cast<std::size_t>(std::floor(q * static_cast<double>(n - 1) + 0.5)));
  std::nth_element(v, v + k, v + n);
  return v[k];
}

}  // namespace

std::uint8_t device_kind(const std::string& device) {
  if (device == "simulated") return DEVICE_SIMULATED;
  if (device == "replay") return DEVICE_REPLAY;
  if (device == "external") return DEVICE_EXTERNAL;
  return DEVICE_HARDWARE;
}

ExperimentPublisher::ExperimentPublisher(dds::Participant& participant, double period_s)
    : writer_(participant, dds::topics::kExperiment), period_s_(period_s) {}

void ExperimentPublisher::begin(const MasterCycle& cycle, std::uint32_t master_session,
                                const std::string& name, const std::string& device,
                                double rate_hz) {
  const MasterCycleConfig& c = cycle.config();
  ExperimentDescription& d = sample_;
  d = ExperimentDescription{};
  d.master_session(master_session);
  d.master_name(name.substr(0, 48));
  d.scheme(c.controller.scheme.substr(0, 32));
  d.mode(static_cast<std::uint8_t>(cycle.controller().scheme()));
  d.wave_impedance_ns_per_m(cycle.controller().wave_impedance_ns_per_m());
  d.rate_hz(rate_hz);
  d.forward_jitter_ms(c.forward.jitter_s * 1e3);
  d.backward_jitter_ms(c.backward.jitter_s * 1e3);
  d.forward_jitter_dist(jitter_dist_name(c.forward));
  d.backward_jitter_dist(jitter_dist_name(c.backward));
  d.forward_loss(c.forward.loss_probability);
  d.backward_loss(c.backward.loss_probability);
  d.forward_burst_p_gb(c.forward.burst_loss ? c.forward.burst_p_good_to_bad : 0.0);
  d.forward_burst_p_bg(c.forward.burst_loss ? c.forward.burst_p_bad_to_good : 0.0);
  d.backward_burst_p_gb(c.backward.burst_loss ? c.backward.burst_p_good_to_bad : 0.0);
  d.backward_burst_p_bg(c.backward.burst_loss ? c.backward.burst_p_bad_to_good : 0.0);
  d.forward_seed(c.forward.seed);
  d.backward_seed(c.backward.seed);
  d.loop_delay_p50_ms(std::numeric_limits<double>::quiet_NaN());
  d.loop_delay_p99_ms(std::numeric_limits<double>::quiet_NaN());
  d.device_kind(device_kind(device));
  d.device(device.substr(0, 48));
  d.driver_timeout_ms(c.driver_timeout_s * 1e3);
  next_ = sample_;
  writer_.prime(sample_);
  window_n_ = 0;
  last_write_s_ = -1.0;
}

void ExperimentPublisher::record_loop_delay(double ms) {
  if (std::isfinite(ms) && window_n_ < kWindow) window_[window_n_++] = ms;
}

void ExperimentPublisher::fill(const MasterCycle& cycle, double now_s,
                               ExperimentDescription& d) const {
  const TuningValues& v = cycle.tuning().current();
  d.master_stiffness_n_per_m(v.master_stiffness_n_per_m);
  d.master_damping_ns_per_m(v.master_damping_ns_per_m);
  d.force_gain(v.force_gain);
  d.slave_stiffness_n_per_m(v.slave_stiffness_n_per_m);
  d.forward_delay_ms(v.forward_delay_s * 1e3);
  d.backward_delay_ms(v.backward_delay_s * 1e3);
  d.driver_live(!cycle.driver_silent());
  d.driver_silences(cycle.driver_silences());
  d.driver_silent_s(cycle.driver_silent_s(now_s));
}

bool ExperimentPublisher::same_setup(const ExperimentDescription& a,
                                     const ExperimentDescription& b) {
  return a.master_stiffness_n_per_m() == b.master_stiffness_n_per_m() &&
         a.master_damping_ns_per_m() == b.master_damping_ns_per_m() &&
         a.force_gain() == b.force_gain() &&
         a.slave_stiffness_n_per_m() == b.slave_stiffness_n_per_m() &&
         a.forward_delay_ms() == b.forward_delay_ms() &&
         a.backward_delay_ms() == b.backward_delay_ms() && a.driver_live() == b.driver_live() &&
         a.driver_silences() == b.driver_silences();
}

bool ExperimentPublisher::update(const MasterCycle& cycle, double now_s, std::int64_t now_ns) {
  fill(cycle, now_s, next_);
  const bool first = last_write_s_ < 0.0;
  const bool due = first || now_s - last_write_s_ >= period_s_;
  if (!due && same_setup(next_, sample_)) return false;
  if (due) {
    // the loop delay of the period just over (none measured: unknown)
    const double nan = std::numeric_limits<double>::quiet_NaN();
    next_.loop_delay_count(window_n_);
    next_.loop_delay_p50_ms(window_n_ > 0 ? quantile(window_.data(), window_n_, 0.5) : nan);
    next_.loop_delay_p99_ms(window_n_ > 0 ? quantile(window_.data(), window_n_, 0.99) : nan);
    window_n_ = 0;
    last_write_s_ = now_s;
  }
  next_.time_ns(now_ns);
  sample_ = next_;
  writer_.write(sample_);
  ++writes_;
  return true;
}

}  // namespace teleop::master
