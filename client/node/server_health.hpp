#pragma once
// What the master knows of the server's health during its session, from ServerStats (counters
// since the server started) and SlaveState: per-session totals that stay right when the server
// restarts (its counters then start again from zero), so the master's summary and verdict
// account for every fault, watchdog trip and overrun on the other side.
#include <cstdint>

namespace teleop::master {

/// A server counter as a per-session total: the first value seen is the baseline (counts from
/// before this session are not ours); after a restart the new server's counts all are.
class SessionCounter {
 public:
  /// Feeds the newest raw value; `restarted`: the server restarted since the last value.
  void feed(std::uint64_t raw, bool restarted = false) {
    if (!any_) {
      base_ = last_ = raw;
      any_ = true;
      return;
    }
    if (restarted || raw < last_) {
      total_ += last_ - base_;
      base_ = 0;
    }
    last_ = raw;
  }
  /// The session's total so far.
  std::uint64_t total() const { return any_ ? total_ + (last_ - base_) : 0; }
  bool any() const { return any_; }

 private:
  std::uint64_t base_ = 0, last_ = 0, total_ = 0;
  bool any_ = false;
};

/// The server's health counters over this session, across restarts.
struct ServerHealth {
  SessionCounter faults;          ///< non-finite states, bodies that blew up and were reset
  SessionCounter watchdog_trips;  ///< no valid command in time: the slave held
  SessionCounter overruns;        ///< physics periods missed
  SessionCounter rejected;        ///< commands rejected (NaN, workspace, stale, passivity)
  std::uint64_t restarts = 0;     ///< server restarts seen (its step counter went back)
  std::uint64_t last_steps = 0;
  bool any = false;

  /// Feeds one ServerStats sample's counters.
  void feed(std::uint64_t steps, std::uint64_t fault_count, std::uint64_t watchdog,
            std::uint64_t overrun_count, std::uint64_t rejected_count) {
    const bool restarted = any && steps < last_steps;
    if (restarted) ++restarts;
    faults.feed(fault_count, restarted);
    watchdog_trips.feed(watchdog, restarted);
    overruns.feed(overrun_count, restarted);
    rejected.feed(rejected_count, restarted);
    last_steps = steps;
    any = true;
  }
};

}  // namespace teleop::master
