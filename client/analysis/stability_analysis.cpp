#include "client/analysis/stability_analysis.hpp"

#include <cmath>

namespace teleop::master {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

std::complex<double> loop_gain(const LoopModel& m, double w) {
  const std::complex<double> s(0.0, w);
  const double k_master =
      m.hand_stiffness_n_per_m + (m.position_position ? m.master_gain_n_per_m : 0.0);
  const std::complex<double> gm =
      1.0 / (m.master_mass_kg * s * s + m.master_damping_ns_per_m * s + k_master);
  const std::complex<double> gs =
      (m.slave_kp_n_per_m + m.slave_kd_ns_per_m * s) /
      (m.slave_mass_kg * s * s +
       (m.slave_kd_ns_per_m + m.slave_damping_ns_per_m + m.env_damping_ns_per_m) * s +
       m.slave_kp_n_per_m + m.env_stiffness_n_per_m);
  if (m.position_position) return -m.master_gain_n_per_m * gm * gs;
  return m.force_gain * (m.env_stiffness_n_per_m + m.env_damping_ns_per_m * s) * gm * gs;
}

namespace {

/// Scans log-spaced frequencies in [w_min, w_max] for the gain crossings |L(jw)| = 1, refines
/// each by bisection and calls on_crossing(wc, phase margin in [0, 2 pi), destabilizing), where
/// destabilizing means |L| falls through 1 with rising w. Stops early when it returns false.
/// Returns whether |L| - 1 was still positive at w_max.
template <class OnCrossing>
bool scan_unit_crossings(const LoopModel& m, double w_min, double w_max, OnCrossing&& on_crossing) {
  constexpr int kSamples = 4000;
  const double lr = std::log(w_max / w_min);
  auto mag1 = [&](double w) { return std::abs(loop_gain(m, w)) - 1.0; };
  double w_prev = w_min;
  double f_prev = mag1(w_prev);
  for (int i = 1; i <= kSamples; ++i) {
    const double w = w_min * std::exp(lr * i / kSamples);
    const double f = mag1(w);
    if ((f_prev > 0.0) != (f > 0.0)) {
      // bisect the crossing |L| = 1
      double a = w_prev, b = w, fa = f_prev;
      for (int k = 0; k < 60; ++k) {
        const double c = 0.5 * (a + b);
        const double fc = mag1(c);
        if ((fa > 0.0) == (fc > 0.0)) {
          a = c;
          fa = fc;
        } else {
          b = c;
        }
      }
      const double wc = 0.5 * (a + b);
      double pm = kPi + std::arg(loop_gain(m, wc));  // in [0, 2 pi]
      pm = std::fmod(pm + 4.0 * kPi, 2.0 * kPi);
      if (!on_crossing(wc, pm, f_prev > 0.0)) return f > 0.0;
    }
    w_prev = w;
    f_prev = f;
  }
  return f_prev > 0.0;
}

}  // namespace

DelayMargin delay_margin(const LoopModel& m, double w_min, double w_max) {
  DelayMargin out;
  out.dc_gain = std::abs(loop_gain(m, 0.0));
  const bool above_at_end = scan_unit_crossings(m, w_min, w_max, [&](double wc, double pm, bool) {
    const double tau = pm / wc;
    if (tau / 2.0 < out.one_way_s) {
      out.one_way_s = tau / 2.0;
      out.crossover_radps = wc;
      out.phase_margin_rad = pm;
    }
    return true;
  });
  // |L| > 1 already at the lowest frequency with the wrong sign: unstable at any delay
  if (above_at_end && out.crossover_radps == 0.0 && out.dc_gain > 1.0) {
    out.one_way_s = 0.0;
  }
  return out;
}

DelayMargin task_delay_margin(const LoopModel& m) {
  LoopModel free = m;
  free.env_stiffness_n_per_m = 0.0;
  free.env_damping_ns_per_m = 0.0;
  const DelayMargin a = delay_margin(m);
  const DelayMargin b = delay_margin(free);
  return a.one_way_s <= b.one_way_s ? a : b;
}

DelayCrossings delay_crossings(const LoopModel& m, double w_min, double w_max) {
  DelayCrossings out;
  scan_unit_crossings(m, w_min, w_max, [&](double wc, double pm, bool destabilizing) {
    DelayCrossing& c = out.items[out.count++];
    c.w_radps = wc;
    c.first_round_trip_s = pm / wc;
    c.destabilizing = destabilizing;  // |L| falls through 1
    return out.count < DelayCrossings::kMax;
  });
  return out;
}

bool stable_at(const DelayCrossings& c, double one_way_s) {
  const double tau = 2.0 * one_way_s;
  int pairs = 0;
  for (int i = 0; i < c.count; ++i) {
    const DelayCrossing& x = c.items[i];
    const double period = 2.0 * kPi / x.w_radps;
    for (double t = x.first_round_trip_s; t < tau; t += period) pairs += x.destabilizing ? 1 : -1;
  }
  return pairs <= 0;
}

bool task_stable_at(const LoopModel& m, double one_way_s) {
  LoopModel free = m;
  free.env_stiffness_n_per_m = 0.0;
  free.env_damping_ns_per_m = 0.0;
  return stable_at(delay_crossings(m), one_way_s) && stable_at(delay_crossings(free), one_way_s);
}

}  // namespace teleop::master
