#pragma once
// Monotonic time helpers. All loop and latency timing uses the steady clock.
#include <chrono>
#include <cstdint>

namespace teleop {

/// Steady-clock time since an arbitrary epoch [ns].
inline std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

/// Seconds between two steady-clock stamps.
inline double seconds_between(std::int64_t from_ns, std::int64_t to_ns) {
  return static_cast<double>(to_ns - from_ns) * 1e-9;
}

}  // namespace teleop
