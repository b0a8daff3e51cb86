#pragma once
// DelayChannel<T>: an injected network impairment for one direction of the teleoperation
// link (master -> slave commands, slave -> master states), in user space (no tc netem).
//
// push(value, now) decides loss (Bernoulli, then Gilbert-Elliott burst), draws the one-way
// delay D + jitter, and schedules delivery at now + delay. Without reordering the delivery
// time is raised to the previous one, so a sample never overtakes an earlier one (FIFO).
// pop(now, out) hands out due samples in delivery order; pop_newest() drains everything due
// and keeps the newest by send order (what a best-effort keep-last-1 DDS reader would see;
// older samples arriving after a newer one are discarded as stale).
//
// Storage is fixed at construction (capacity slots, a binary heap of indices); push/pop
// never allocate. Randomness comes from PortableRng (mt19937_64 + hand-written
// distributions): the same seed gives the same losses and delays on every platform.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "client/net/delay_config.hpp"
#include "common/util/stats.hpp"

namespace teleop::master {

/// Counters of a channel (all since construction or reset()).
struct ChannelCounters {
  std::uint64_t pushed = 0;         ///< samples offered
  std::uint64_t delivered = 0;      ///< samples handed out by pop()/pop_newest()
  std::uint64_t lost_random = 0;    ///< dropped by the Bernoulli loss
  std::uint64_t lost_burst = 0;     ///< dropped in the Gilbert-Elliott bad state
  std::uint64_t lost_overflow = 0;  ///< dropped because capacity samples were in flight
  std::uint64_t lost_window = 0;    ///< dropped in the scheduled loss window
  std::uint64_t superseded = 0;     ///< due but replaced by a newer one in pop_newest()
  std::uint64_t stale = 0;          ///< arrived after a newer one was delivered (discarded)
  std::uint64_t reordered = 0;      ///< delivered with a lower seq than an earlier delivery
  double delay_sum_s = 0.0;         ///< sum of observed delays (pop time - push time) [s]
  double delay_sum_sq_s2 = 0.0;     ///< sum of squared observed delays [s^2]
  double delay_max_s = 0.0;         ///< largest observed delay [s]

  /// Fraction of pushed samples lost (random + burst + overflow + window).
  double loss_fraction() const {
    return pushed ? static_cast<double>(lost_random + lost_burst + lost_overflow + lost_window) /
                        static_cast<double>(pushed)
                  : 0.0;
  }
  /// Mean observed delay [s].
  double delay_mean_s() const {
    return delivered ? delay_sum_s / static_cast<double>(delivered) : 0.0;
  }
  /// Standard deviation of the observed delay [s].
  double delay_stddev_s() const {
    if (delivered < 2) return 0.0;
    const double n = static_cast<double>(delivered);
    const double m = delay_sum_s / n;
    return std::sqrt(std::max(0.0, delay_sum_sq_s2 / n - m * m));
  }
};

/// Report of a channel with percentiles (computed outside the hot loop: allocates).
struct ChannelReport {
  ChannelCounters counters;
  double delay_mean_ms = 0.0;  ///< observed one-way delay, mean [ms]
  double delay_std_ms = 0.0;   ///< standard deviation [ms]
  double delay_p50_ms = 0.0;   ///< median [ms]
  double delay_p99_ms = 0.0;   ///< 99th percentile [ms]
  double delay_max_ms = 0.0;   ///< maximum [ms]
  double loss_fraction = 0.0;  ///< lost / pushed
};

/// One direction of an impaired link carrying values of type T (copyable). See file comment.
template <class T>
class DelayChannel {
 public:
  /// Allocates all storage. @throws config::ConfigError if `cfg` is invalid.
  explicit DelayChannel(const DelayConfig& cfg, std::size_t delay_window = 1 << 16)
      : cfg_(validated(cfg)),
        rng_(cfg.seed),
        slots_(cfg.capacity),
        heap_(cfg.capacity),
        free_(cfg.capacity),
        window_(delay_window) {
    reset();
  }

  /// Empties the channel, clears the counters and reseeds (same seed: same future).
  void reset() {
    rng_.seed(cfg_.seed);
    heap_size_ = 0;
    free_count_ = slots_.size();
    for (std::size_t i = 0; i < free_.size(); ++i) free_[i] = static_cast<std::uint32_t>(i);
    counters_ = {};
    window_.clear();
    bad_state_ = false;
    last_due_s_ = -1e300;
    next_seq_ = 0;
    newest_delivered_seq_ = 0;
    any_delivered_ = false;
    any_pushed_ = false;
    origin_s_ = 0.0;
  }

  /// Sets the constant one-way delay D of samples pushed from now on [s] (live tuning; the
  /// caller slews it, see client/control/tuning.hpp). Samples in flight keep their delivery
  /// times; without reordering a shorter delay still never lets a sample overtake. Real-time safe.
  void set_delay_s(double delay_s) { cfg_.delay_s = std::clamp(delay_s, 0.0, 10.0); }

  /// Offers a sample sent at `now_s` [s]. Returns false if it was lost. Never allocates.
  bool push(const T& value, double now_s) {
    ++counters_.pushed;
    const std::uint64_t seq = ++next_seq_;
    // Gilbert-Elliott: advance the two-state chain once per sample, lose all in the bad state
    if (cfg_.burst_loss) {
      if (bad_state_) {
        if (rng_.bernoulli(cfg_.burst_p_bad_to_good)) bad_state_ = false;
      } else {
        if (rng_.bernoulli(cfg_.burst_p_good_to_bad)) bad_state_ = true;
      }
    }
    // draw the Bernoulli loss and the delay for every sample, lost or not, so that the
    // random stream (and hence the delays of later samples) does not depend on the losses
    const bool lost_random = rng_.bernoulli(cfg_.loss_probability);
    double delay = draw_delay();
    // the scheduled faults, timed from the first sample (no draw unless a window is set, so a
    // channel without one keeps its random stream)
    if (!any_pushed_) {
      any_pushed_ = true;
      origin_s_ = now_s;
    }
    const double since_s = now_s - origin_s_;
    bool lost_window = false;
    if (cfg_.window_duration_s > 0.0 && cfg_.window_loss > 0.0) {
      const bool draw = rng_.bernoulli(cfg_.window_loss);
      lost_window = draw && since_s >= cfg_.window_at_s &&
                    since_s < cfg_.window_at_s + cfg_.window_duration_s;
    }
    if (cfg_.spike_duration_s > 0.0 && since_s >= cfg_.spike_at_s &&
        since_s < cfg_.spike_at_s + cfg_.spike_duration_s) {
      delay += cfg_.spike_extra_s;
    }
    if (lost_window) {
      ++counters_.lost_window;
      return false;
    }
    if (cfg_.burst_loss && bad_state_) {
      ++counters_.lost_burst;
      return false;
    }
    if (lost_random) {
      ++counters_.lost_random;
      return false;
    }
    if (free_count_ == 0) {
      ++counters_.lost_overflow;
      return false;
    }
    double due = now_s + delay;
    if (!cfg_.reorder) due = std::max(due, last_due_s_);  // FIFO: never overtake
    last_due_s_ = std::max(last_due_s_, due);
    const std::uint32_t slot = free_[--free_count_];
    slots_[slot].value = value;
    slots_[slot].send_s = now_s;
    slots_[slot].due_s = due;
    slots_[slot].seq = seq;
    heap_push(slot);
    return true;
  }

  /// Hands out the earliest sample due at `now_s` (delivery order). False if none is due.
  bool pop(double now_s, T& out) {
    if (heap_size_ == 0 || slots_[heap_[0]].due_s > now_s) return false;
    const std::uint32_t slot = heap_pop();
    out = slots_[slot].value;
    deliver(slots_[slot], now_s);
    free_[free_count_++] = slot;
    return true;
  }

  /// Drains all samples due at `now_s` and returns the newest by send order in `out`
  /// (older ones count as superseded; ones older than a sample already delivered are
  /// discarded as stale). False if nothing new arrived. Never allocates.
  bool pop_newest(double now_s, T& out) {
    bool got = false;
    while (heap_size_ > 0 && slots_[heap_[0]].due_s <= now_s) {
      const std::uint32_t slot = heap_pop();
      Slot& s = slots_[slot];
      if (any_delivered_ && s.seq < newest_delivered_seq_) {
        ++counters_.stale;
      } else {
        if (got) ++counters_.superseded;
        out = s.value;
        deliver(s, now_s);
        got = true;
      }
      free_[free_count_++] = slot;
    }
    return got;
  }

  /// Samples in flight.
  std::size_t in_flight() const { return heap_size_; }
  /// The configuration in use.
  const DelayConfig& config() const { return cfg_; }
  /// Counters (cheap, real-time safe).
  const ChannelCounters& counters() const { return counters_; }
  /// Full report with percentiles of the newest observed delays. Allocates.
  ChannelReport report() const {
    ChannelReport r;
    r.counters = counters_;
    r.delay_mean_ms = counters_.delay_mean_s() * 1e3;
    r.delay_std_ms = counters_.delay_stddev_s() * 1e3;
    r.delay_max_ms = counters_.delay_max_s * 1e3;
    r.loss_fraction = counters_.loss_fraction();
    if (window_.size() > 0) {
      const auto v = window_.snapshot();
      r.delay_p50_ms = percentile(v, 50.0) * 1e3;
      r.delay_p99_ms = percentile(v, 99.0) * 1e3;
    }
    return r;
  }

 private:
  static const DelayConfig& validated(const DelayConfig& c) {
    c.validate();
    return c;
  }

  struct Slot {
    T value{};
    double send_s = 0.0;
    double due_s = 0.0;
    std::uint64_t seq = 0;
  };

  double draw_delay() {
    double d = cfg_.delay_s;
    if (cfg_.jitter_s > 0.0) {
      if (cfg_.jitter_dist == JitterDist::kUniform) {
        d += rng_.uniform(-cfg_.jitter_s, cfg_.jitter_s);
      } else {
        d += std::clamp(rng_.normal(), -4.0, 4.0) * cfg_.jitter_s;
      }
    }
    return std::max(0.0, d);
  }

  void deliver(const Slot& s, double now_s) {
    const double d = now_s - s.send_s;
    ++counters_.delivered;
    counters_.delay_sum_s += d;
    counters_.delay_sum_sq_s2 += d * d;
    counters_.delay_max_s = std::max(counters_.delay_max_s, d);
    window_.record(d);
    if (any_delivered_ && s.seq < newest_delivered_seq_) ++counters_.reordered;
    if (!any_delivered_ || s.seq > newest_delivered_seq_) newest_delivered_seq_ = s.seq;
    any_delivered_ = true;
  }

  // binary min-heap on (due_s, seq) over slot indices
  bool before(std::uint32_t a, std::uint32_t b) const {
    const Slot& x = slots_[a];
    const Slot& y = slots_[b];
    return x.due_s < y.due_s || (x.due_s == y.due_s && x.seq < y.seq);
  }
  void heap_push(std::uint32_t slot) {
    std::size_t i = heap_size_++;
    heap_[i] = slot;
    while (i > 0) {
      const std::size_t parent = (i - 1) / 2;
      if (!before(heap_[i], heap_[parent])) break;
      std::swap(heap_[i], heap_[parent]);
      i = parent;
    }
  }
  std::uint32_t heap_pop() {
    const std::uint32_t top = heap_[0];
    heap_[0] = heap_[--heap_size_];
    std::size_t i = 0;
    while (true) {
      const std::size_t l = 2 * i + 1, r = l + 1;
      std::size_t m = i;
      if (l < heap_size_ && before(heap_[l], heap_[m])) m = l;
      if (r < heap_size_ && before(heap_[r], heap_[m])) m = r;
      if (m == i) break;
      std::swap(heap_[i], heap_[m]);
      i = m;
    }
    return top;
  }

  DelayConfig cfg_;
  PortableRng rng_;
  std::vector<Slot> slots_;
  std::vector<std::uint32_t> heap_;
  std::vector<std::uint32_t> free_;
  std::size_t heap_size_ = 0;
  std::size_t free_count_ = 0;
  ChannelCounters counters_;
  SampleWindow window_;
  bool bad_state_ = false;
  double last_due_s_ = -1e300;
  std::uint64_t next_seq_ = 0;
  std::uint64_t newest_delivered_seq_ = 0;
  bool any_delivered_ = false;
  bool any_pushed_ = false;  ///< the first sample fixed origin_s_
  double origin_s_ = 0.0;    ///< send time of the first sample [s] (scheduled faults count from it)
};

}  // namespace teleop::master
