#pragma once
// A fixed-rate loop driver on the steady clock with absolute deadlines, so jitter does
// not accumulate. Counts overruns (deadlines already passed when a period ends) and
// records the wake-up lateness for jitter statistics.
#include <cstdint>

#include "common/util/stats.hpp"

namespace teleop {

class RateLoop {
 public:
  /// rate_hz > 0. `jitter_capacity` samples of wake-up lateness are kept. `spin_ns` > 0: sleep
  /// until that long before each deadline, then busy-wait to it (the core stays awake and its
  /// caches warm, at the price of that much CPU per period); 0 sleeps to the deadline.
  explicit RateLoop(double rate_hz, std::size_t jitter_capacity = 65536, std::int64_t spin_ns = 0);

  /// Waits until the next period boundary. Returns false when the deadline had already
  /// passed (an overrun); the schedule then skips the missed periods instead of bursting.
  bool wait();
  /// Sleeps until `lead_ns` before the next deadline (at once when that time has passed), for
  /// work that must end just before the deadline (a prewarm); wait() then finishes the period.
  void sleep_until_lead(std::int64_t lead_ns);

  double period_s() const { return static_cast<double>(period_ns_) * 1e-9; }
  std::int64_t period_ns() const { return period_ns_; }
  std::int64_t spin_ns() const { return spin_ns_; }
  std::uint64_t overruns() const { return overruns_; }
  std::uint64_t iterations() const { return iterations_; }
  /// Lateness of each wake-up relative to its deadline [us].
  const SampleWindow& lateness_us() const { return lateness_us_; }
  /// Restarts the schedule from now.
  void reset();

 private:
  std::int64_t period_ns_;
  std::int64_t next_ns_;
  std::int64_t spin_ns_;
  std::uint64_t overruns_ = 0;
  std::uint64_t iterations_ = 0;
  SampleWindow lateness_us_;
};

}  // namespace teleop
