#pragma once
// The master's loop delay: from a command's entry into the injected forward channel to the cycle
// whose controller uses its echo (the SlaveState that names the command's seq). It includes both
// injected delays, the network both ways and the server's step; the round trip (DdsSlaveLink)
// is the network's part alone.
#include <cmath>
#include <cstdint>
#include <vector>

#include "common/util/stats.hpp"

namespace teleop::master {

/// Remembers the entry times of the newest kEntryRing commands; allocates only when made, so
/// entered() and echo_used() may run in the haptic loop.
class LoopDelayMeter {
 public:
  /// Commands whose entry time is remembered.
  static constexpr std::uint64_t kEntryRing = 1 << 16;
  /// Loop delays kept for the summary (the newest ones when there are more).
  static constexpr std::size_t kWindow = 1 << 20;

  LoopDelayMeter() : entry_time_s_(kEntryRing, 0.0), window_ms_(kWindow) {}
  /// Command `seq` entered the forward channel at `now_s` [s].
  void entered(std::uint64_t seq, double now_s) { entry_time_s_[seq % kEntryRing] = now_s; }
  /// The controller used the echo of command `echoed` at `now_s` [s] while `newest` is the newest
  /// command. Returns true and records the delay (last_ms()) when the echo is newer than the last
  /// one used, older than `newest`, and its entry time is still remembered.
  bool echo_used(std::uint64_t echoed, std::uint64_t newest, double now_s) {
    if (echoed <= last_used_seq_ || echoed >= newest || echoed + kEntryRing <= newest) {
      return false;
    }
    last_used_seq_ = echoed;
    last_ms_ = (now_s - entry_time_s_[echoed % kEntryRing]) * 1e3;
    window_ms_.record(last_ms_);
    return true;
  }
  /// The newest loop delay (NaN before the first) [ms].
  double last_ms() const { return last_ms_; }
  /// Over the session (allocates: not in the loop).
  Summary summary() const { return summarize(window_ms_.snapshot()); }

 private:
  std::vector<double> entry_time_s_;
  SampleWindow window_ms_;
  std::uint64_t last_used_seq_ = 0;
  double last_ms_ = std::nan("");
};

}  // namespace teleop::master
