#pragma once
// The words every observer shows for teleop/experiment (ExperimentDescription): one line with
// the scheme, the gains in force, the injected impairment of each direction, the loop delay the
// controller lives with and the device. teleop_monitor prints it as it is; teleop_viewer shows
// it in its overlay. Header-only: the observers' libraries include it with the IDL types.
#include <cmath>
#include <cstdio>
#include <string>

#include "teleop/idl/Teleop.h"

namespace teleop::dds {

namespace detail {

/// "a" when both directions agree, else "a/b" (each with `digits` significant digits).
inline std::string both_ways(int digits, double a, double b) {
  char x[48], y[48];
  std::snprintf(x, sizeof(x), "%.*g", digits, a);
  std::snprintf(y, sizeof(y), "%.*g", digits, b);
  return std::string(x) == y ? std::string(x) : std::string(x) + "/" + y;
}

inline std::string ms_or_na(double v) {
  if (!std::isfinite(v)) return "n/a";
  char b[32];
  std::snprintf(b, sizeof(b), "%.1f", v);
  return b;
}

}  // namespace detail

/// One line describing the experiment, e.g.
/// "force-position K_pm 2000 N/m B_m 2.0 N s/m K_f 1.00 K_ps 2000 N/m | delay 50 ms jitter
///  5 ms uniform loss 2 % burst off seed 1/2 | loop delay p50 101.3 ms p99 104.0 ms | device
///  external live". Directions that differ print as forward/backward.
inline std::string experiment_text(const ExperimentDescription& e) {
  using detail::both_ways;
  std::string gains;
  char buf[256];
  std::snprintf(buf, sizeof(buf), "%s K_pm %.0f N/m B_m %.1f N s/m K_f %.2f K_ps %.0f N/m",
                e.scheme().c_str(), e.master_stiffness_n_per_m(), e.master_damping_ns_per_m(),
                e.force_gain(), e.slave_stiffness_n_per_m());
  gains = buf;
  if (e.wave_impedance_ns_per_m() > 0.0) {
    std::snprintf(buf, sizeof(buf), " b %.1f N s/m", e.wave_impedance_ns_per_m());
    gains += buf;
  }
  std::string net = "delay " + both_ways(4, e.forward_delay_ms(), e.backward_delay_ms()) +
                    " ms jitter " + both_ways(4, e.forward_jitter_ms(), e.backward_jitter_ms()) +
                    " ms";
  if (e.forward_jitter_ms() > 0.0 || e.backward_jitter_ms() > 0.0) {
    const std::string fd = e.forward_jitter_dist().c_str(), bd = e.backward_jitter_dist().c_str();
    net += " " + (fd == bd ? fd : fd + "/" + bd);
  }
  net += " loss " + both_ways(3, 100.0 * e.forward_loss(), 100.0 * e.backward_loss()) + " %";
  if (e.forward_burst_p_gb() > 0.0 || e.backward_burst_p_gb() > 0.0) {
    net += " burst " + both_ways(3, e.forward_burst_p_gb(), e.backward_burst_p_gb()) + "," +
           both_ways(3, e.forward_burst_p_bg(), e.backward_burst_p_bg());
  } else {
    net += " burst off";
  }
  net += " seed " + std::to_string(e.forward_seed()) +
         (e.backward_seed() != e.forward_seed() ? "/" + std::to_string(e.backward_seed()) : "");
  const std::string loop = "loop delay p50 " + detail::ms_or_na(e.loop_delay_p50_ms()) +
                           " ms p99 " + detail::ms_or_na(e.loop_delay_p99_ms()) + " ms";
  std::string device = "device " + std::string(e.device().c_str());
  if (e.driver_live()) {
    device += " live";
  } else {
    device += " SILENT: slave held";
  }
  if (e.driver_silences() > 0) {
    std::snprintf(buf, sizeof(buf), " (silent %llu times, %.2f s)",
                  static_cast<unsigned long long>(e.driver_silences()), e.driver_silent_s());
    device += buf;
  }
  return gains + " | " + net + " | " + loop + " | " + device;
}

}  // namespace teleop::dds
