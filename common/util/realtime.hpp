#pragma once
// Real-time scheduling of a loop thread (teleop_server's physics loop, teleop_master's haptic
// loop): SCHED_FIFO at a priority, optionally pinned to one CPU, and the process's current pages
// locked in memory. A loop that sleeps to absolute deadlines (RateLoop) then wakes on time even
// when other processes keep the cores busy; measured in docs/results.md ("Live session").
#include <string>

namespace teleop {

/// What to ask for. priority 0 = stay SCHED_OTHER; cpu < 0 = no pinning.
struct RealtimeOptions {
  int priority = 0;         ///< SCHED_FIFO priority, 1-99
  int cpu = -1;             ///< pin the calling thread to this CPU
  int spin_us = 0;          ///< busy-wait this long before each deadline (RateLoop), 0 = sleep
  int dma_latency_us = -1;  ///< hold /dev/cpu_dma_latency at this value while the loop runs
  /// read the next step's data into the caches during this long before each deadline, 0 = no
  int prewarm_us = 0;
  /// lock the process's pages, present and future, in memory and pre-fault the loop's stack
  /// (implied by priority > 0, which locks the present pages)
  bool lock_memory = false;
  /// with priority 0: the loop thread's nice value, -20 to 19 (0 = unchanged; a normal thread
  /// whose weight is up to 86 times a nice-0 thread's)
  int nice = 0;
};

/// Holds /dev/cpu_dma_latency at a value for its lifetime (the kernel then keeps the cores out
/// of idle states whose exit latency exceeds it); the request ends when the holder is
/// destroyed. A value < 0 holds nothing.
class DmaLatencyHold {
 public:
  DmaLatencyHold() = default;
  /// Opens and writes the request; `problem()` says why when it could not.
  explicit DmaLatencyHold(int latency_us);
  ~DmaLatencyHold();
  DmaLatencyHold(const DmaLatencyHold&) = delete;
  DmaLatencyHold& operator=(const DmaLatencyHold&) = delete;
  DmaLatencyHold(DmaLatencyHold&& o) noexcept;
  DmaLatencyHold& operator=(DmaLatencyHold&& o) noexcept;

  bool held() const { return fd_ >= 0; }
  const std::string& problem() const { return problem_; }

 private:
  int fd_ = -1;
  std::string problem_;
};

/// True when make_thread_realtime has something to do for `o` (priority, pinning or locking).
inline bool wants_thread_setup(const RealtimeOptions& o) {
  return o.priority > 0 || o.cpu >= 0 || o.lock_memory || o.nice != 0;
}

/// Applies `o` to the calling thread. Returns "" on success, else what failed and why (the
/// caller reports it and goes on as a normal thread: a missing privilege is not fatal).
std::string make_thread_realtime(const RealtimeOptions& o);

}  // namespace teleop
