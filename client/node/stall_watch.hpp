#pragma once
// A stall of the master's own haptic loop, detected from the clock: a cycle that begins
// kStallS or more after the previous one (the process was stopped, starved or swapped out, and
// the device held its last force meanwhile). The node fades the force out and back in and
// publishes an event; the count and the longest gap go into the summary.
#include <algorithm>
#include <cstdint>

namespace teleop::master {

class StallWatch {
 public:
  /// The gap between two cycles' starts that is a stall [s]; far above any overrun of a loaded
  /// machine (tens of ms).
  static constexpr double kStallS = 0.2;

  /// A cycle begins at `now_s` [s]. Returns the gap since the previous cycle began when it is a
  /// stall (then counted) [s], else 0; the first cycle is never one.
  double cycle_began(double now_s) {
    const bool first = !started_;
    const double gap_s = now_s - prev_s_;
    started_ = true;
    prev_s_ = now_s;
    if (first || gap_s < kStallS) return 0.0;
    ++stalls_;
    longest_s_ = std::max(longest_s_, gap_s);
    return gap_s;
  }
  /// Stalls so far.
  std::uint64_t stalls() const { return stalls_; }
  /// The longest stall so far [s] (0 when none).
  double longest_s() const { return longest_s_; }

 private:
  bool started_ = false;
  double prev_s_ = 0.0;  // when the previous cycle began [s]
  std::uint64_t stalls_ = 0;
  double longest_s_ = 0.0;
};

}  // namespace teleop::master
