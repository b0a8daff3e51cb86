#pragma once
// Round-trip bookkeeping without synchronised clocks: SlaveState echoes the command's seq and
// send time, so the master measures RTT on its own steady clock.
#include <cstdint>

#include "common/util/stats.hpp"

namespace teleop::master {

class RttTracker {
 public:
  explicit RttTracker(std::size_t capacity = 1 << 20) : rtt_ms_(capacity) {}

  /// Called for each received SlaveState. Returns the RTT [ms] if this echo is new
  /// (a command seq not seen before), or a negative number for a repeat/stale echo.
  /// Echoes of seq 0 (no command applied yet) or of a seq above `newest_sent_seq` (from an
  /// earlier master session) are ignored.
  double on_echo(std::uint64_t command_seq, std::int64_t command_send_time_ns, std::int64_t now_ns,
                 std::uint64_t newest_sent_seq);

  const SampleWindow& rtt_ms() const { return rtt_ms_; }
  std::uint64_t unique_echoes() const { return unique_; }
  std::uint64_t newest_echoed_seq() const { return newest_seq_; }

 private:
  SampleWindow rtt_ms_;
  std::uint64_t newest_seq_ = 0;
  bool any_ = false;
  std::uint64_t unique_ = 0;
};

}  // namespace teleop::master
