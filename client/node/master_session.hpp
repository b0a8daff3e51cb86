#pragma once
// The master's session bookkeeping across the haptic loop's cycles (MasterNode): when the loop is
// over, which cycles publish MasterState, when the server's faults make the session unstable,
// the link losses and stalls it counts, ownership (OwnershipWatch) and the loop delay
// (LoopDelayMeter), and the loop's figures in the report. It reads numbers the node hands it (the
// clock, the cycle's homing, the server's fault count, the link's state) and holds no DDS object,
// so a test drives it with a fake clock. Made before the first cycle; a cycle allocates nothing.
#include <cstdint>

#include "client/node/loop_delay_meter.hpp"
#include "client/node/ownership_watch.hpp"
#include "client/node/stall_watch.hpp"

namespace teleop::master {

struct MasterOptions;
struct SessionReport;

/// The loop's pace and length, fixed from the options before the first cycle.
struct SessionPlan {
  std::uint64_t samples = 0;      ///< the loop ends after this many cycles (0: no limit)
  std::uint64_t state_every = 1;  ///< MasterState every this many cycles (0 reads as 1)
  double session_length_s = 0.0;  ///< the session after homing [s]
  double grace_s = 0.0;           ///< how long the first commands' answer may take [s]
  double wait_owner_s = 0.0;      ///< how long a refused master waits for the slave [s]
};

/// The plan for `options`: --duration, else the simulated script's length + 1 s (2 s at least),
/// else 10 s; MasterState at state_rate_hz; a grace of 0.5 s plus twice the injected delays.
SessionPlan plan_session(const MasterOptions& options);

class MasterSession {
 public:
  /// `t0_ns`: the loop's start on the steady clock [ns].
  MasterSession(const SessionPlan& plan, std::int64_t t0_ns);

  const SessionPlan& plan() const { return plan_; }
  /// The loop's start [ns] and [s].
  std::int64_t t0_ns() const { return t0_ns_; }
  double t0_s() const { return t0_s_; }
  /// Cycles begun so far.
  std::uint64_t cycles() const { return cycles_; }

  /// Whether the loop is over at `now_s` [s]: the sample limit reached, a refusal given up on,
  /// or the session length past since the session began after homing (`homing`: the cycle still
  /// homes; `session_start_s`: when the session began [s]).
  bool over(double now_s, bool homing, double session_start_s) const;
  /// A cycle begins at `now_s` [s]: counted. Returns the stall's gap when it is one (StallWatch)
  /// [s], else 0.
  double begin_cycle(double now_s);
  /// The server's faults since the master started (ServerHealth and ServerWord; the baseline
  /// from before the session already taken out). True when more than seen before: the session
  /// is not stable.
  bool faults_rose(std::uint64_t faults);
  /// The link's state after a cycle; a loss is counted when it begins.
  void link_state(bool lost);
  /// This cycle publishes MasterState.
  bool state_due() const { return cycles_ % plan_.state_every == 0; }

  OwnershipWatch& owner() { return owner_; }
  const OwnershipWatch& owner() const { return owner_; }
  LoopDelayMeter& loop_delay() { return loop_delay_; }
  const LoopDelayMeter& loop_delay() const { return loop_delay_; }
  const StallWatch& stalls() const { return stalls_; }
  std::uint64_t link_losses() const { return link_losses_; }

  /// The loop's figures at `end_s` [s] into `rep`: elapsed and session time (`session_start_s`
  /// < 0: the session never began), the loop delay, ownership, stalls and link losses
  /// (allocates: after the loop).
  void report(double end_s, double session_start_s, SessionReport& rep) const;

 private:
  SessionPlan plan_;
  std::int64_t t0_ns_;
  double t0_s_;
  std::uint64_t cycles_ = 0;
  std::uint64_t faults_seen_ = 0;
  bool link_lost_ = false;
  std::uint64_t link_losses_ = 0;
  StallWatch stalls_;
  OwnershipWatch owner_;
  LoopDelayMeter loop_delay_;
};

}  // namespace teleop::master
