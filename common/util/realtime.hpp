#pragma once
// Real-time scheduling of a loop thread (teleop_server's physics loop, teleop_master's haptic
// loop): SCHED_FIFO at a priority, optionally pinned to one CPU, and the process's current pages
// locked in memory. A loop that sleeps to absolute deadlines (RateLoop) then wakes on time even
// when other processes keep the cores busy; measured in docs/results.md ("Live session").
#include <string>

namespace teleop {

/// What to ask for. priority 0 = stay SCHED_OTHER; cpu < 0 = no pinning.
struct RealtimeOptions {
  int priority = 0;  ///< SCHED_FIFO priority, 1-99
  int cpu = -1;      ///< pin the calling thread to this CPU
};

/// Applies `o` to the calling thread. Returns "" on success, else what failed and why (the
/// caller reports it and goes on as a normal thread: a missing privilege is not fatal).
std::string make_thread_realtime(const RealtimeOptions& o);

}  // namespace teleop
