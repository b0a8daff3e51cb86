#include "client/control/tuning.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace teleop::master {

namespace {

constexpr std::uint32_t kDelays = kTuneForwardDelay | kTuneBackwardDelay;

struct FieldInfo {
  TuningField bit;
  const char* name;  // as in the YAML and the IDL
  const char* unit;
  double scale;  // value as shown = value * scale (delays in ms)
};

constexpr FieldInfo kFields[] = {
    {kTuneMasterStiffness, "master_stiffness_n_per_m", "N/m", 1.0},
    {kTuneMasterDamping, "master_damping_ns_per_m", "N s/m", 1.0},
    {kTuneForceGain, "force_gain", "", 1.0},
    {kTuneSlaveStiffness, "slave_stiffness_n_per_m", "N/m", 1.0},
    {kTuneForwardDelay, "forward_delay_ms", "ms", 1e3},
    {kTuneBackwardDelay, "backward_delay_ms", "ms", 1e3},
};

double value_of(const TuningValues& v, TuningField f) {
  switch (f) {
    case kTuneMasterStiffness:
      return v.master_stiffness_n_per_m;
    case kTuneMasterDamping:
      return v.master_damping_ns_per_m;
    case kTuneForceGain:
      return v.force_gain;
    case kTuneSlaveStiffness:
      return v.slave_stiffness_n_per_m;
    case kTuneForwardDelay:
      return v.forward_delay_s;
    case kTuneBackwardDelay:
      return v.backward_delay_s;
    default:
      return 0.0;
  }
}

double max_of(const TuningLimits& l, TuningField f) {
  switch (f) {
    case kTuneMasterStiffness:
      return l.max_master_stiffness_n_per_m;
    case kTuneMasterDamping:
      return l.max_master_damping_ns_per_m;
    case kTuneForceGain:
      return l.max_force_gain;
    case kTuneSlaveStiffness:
      return l.max_slave_stiffness_n_per_m;
    default:
      return l.max_delay_s;
  }
}

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.4g", v);
  return buf;
}

double lerp(double a, double b, double s) { return a + (b - a) * s; }

}  // namespace

std::uint32_t tunable_fields(const ControllerParams& p) {
  return scheme_traits(p).tunable_gains | kDelays;
}

TuningLimits tuning_limits(const ControllerParams& params, const DeviceSpec& spec,
                           std::size_t channel_capacity, double dt_s) {
  TuningLimits l;
  l.tunable = tunable_fields(params);
  l.max_master_stiffness_n_per_m = spec.max_stiffness_n_per_m;
  l.max_master_damping_ns_per_m = spec.max_damping_ns_per_m;
  l.max_force_gain = 10.0;
  l.max_slave_stiffness_n_per_m = 5000.0;
  l.max_delay_s = std::min(2.0, 0.8 * static_cast<double>(channel_capacity) * dt_s);
  return l;
}

std::string check_tuning(const TuningRequestData& r, const TuningLimits& l,
                         const std::string& scheme) {
  if (r.fields == 0) return "the request sets no field";
  if ((r.fields & ~static_cast<std::uint32_t>(kTuneAll)) != 0) {
    return "unknown field bits " + std::to_string(r.fields & ~static_cast<std::uint32_t>(kTuneAll));
  }
  if (!std::isfinite(r.ramp_s) || r.ramp_s < 0.0 || r.ramp_s > l.max_ramp_s) {
    return "ramp_s = " + number(r.ramp_s) + " is outside [0, " + number(l.max_ramp_s) + "] s";
  }
  for (const FieldInfo& f : kFields) {
    if ((r.fields & f.bit) == 0) continue;
    if ((l.tunable & f.bit) == 0) {
      return std::string(f.name) + " is not used by the " + scheme + " scheme";
    }
    const double v = value_of(r.values, f.bit);
    const double hi = max_of(l, f.bit);
    if (!std::isfinite(v) || v < 0.0 || v > hi) {
      return std::string(f.name) + " = " + number(v * f.scale) + " is outside [0, " +
             number(hi * f.scale) + "]" + (*f.unit ? std::string(" ") + f.unit : std::string());
    }
  }
  return {};
}

std::string describe_tuning(const TuningRequestData& r, const TuningValues& from, double ramp_s) {
  std::string out;
  for (const FieldInfo& f : kFields) {
    if ((r.fields & f.bit) == 0) continue;
    if (!out.empty()) out += ", ";
    out += std::string(f.name) + " " + number(value_of(from, f.bit) * f.scale) + " -> " +
           number(value_of(r.values, f.bit) * f.scale);
  }
  out += " over " + number(ramp_s) + " s";
  if (r.fields & kDelays) {
    out += " (a delay moves at most " + number(kMaxDelaySlewSPerS * 1e3) + " ms per s)";
  }
  return out;
}

void TuningRamp::start(const TuningRequestData& r, double now_s, double min_ramp_s) {
  from_ = current_;
  const TuningValues& v = r.values;
  if (r.fields & kTuneMasterStiffness)
    target_.master_stiffness_n_per_m = v.master_stiffness_n_per_m;
  if (r.fields & kTuneMasterDamping) target_.master_damping_ns_per_m = v.master_damping_ns_per_m;
  if (r.fields & kTuneForceGain) target_.force_gain = v.force_gain;
  if (r.fields & kTuneSlaveStiffness) target_.slave_stiffness_n_per_m = v.slave_stiffness_n_per_m;
  if (r.fields & kTuneForwardDelay) target_.forward_delay_s = v.forward_delay_s;
  if (r.fields & kTuneBackwardDelay) target_.backward_delay_s = v.backward_delay_s;
  ramp_s_ = std::max(r.ramp_s, min_ramp_s);
  // a delay moves at most kMaxDelaySlewSPerS: its own, possibly longer, ramp
  forward_ramp_s_ = std::max(
      ramp_s_, std::abs(target_.forward_delay_s - from_.forward_delay_s) / kMaxDelaySlewSPerS);
  backward_ramp_s_ = std::max(
      ramp_s_, std::abs(target_.backward_delay_s - from_.backward_delay_s) / kMaxDelaySlewSPerS);
  start_s_ = now_s;
  active_ = true;
}

bool TuningRamp::advance(double now_s) {
  if (!active_) return false;
  const double t = now_s - start_s_;
  const double s = std::clamp(t / ramp_s_, 0.0, 1.0);
  current_.master_stiffness_n_per_m =
      lerp(from_.master_stiffness_n_per_m, target_.master_stiffness_n_per_m, s);
  current_.master_damping_ns_per_m =
      lerp(from_.master_damping_ns_per_m, target_.master_damping_ns_per_m, s);
  current_.force_gain = lerp(from_.force_gain, target_.force_gain, s);
  current_.slave_stiffness_n_per_m =
      lerp(from_.slave_stiffness_n_per_m, target_.slave_stiffness_n_per_m, s);
  current_.forward_delay_s = lerp(from_.forward_delay_s, target_.forward_delay_s,
                                  std::clamp(t / forward_ramp_s_, 0.0, 1.0));
  current_.backward_delay_s = lerp(from_.backward_delay_s, target_.backward_delay_s,
                                   std::clamp(t / backward_ramp_s_, 0.0, 1.0));
  if (t >= std::max({ramp_s_, forward_ramp_s_, backward_ramp_s_})) {
    current_ = target_;
    active_ = false;
  }
  return true;
}

}  // namespace teleop::master
