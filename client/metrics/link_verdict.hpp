#pragma once
// The link's part of a session's verdict. A session whose loop stayed stable is still not
// "stable" when the link did not carry it:
//   - lost:      more than max_lost_fraction of the commands that left the master's loop never
//                reached the server (injected loss counts: the slave never saw them); commands
//                still held in the injected delay when the master stopped are in flight, not
//                lost, and are left out of the fraction; commands the server rejected reached
//                it, so the server's rejections are taken off the lost ones, and when most were
//                rejected the loss is not judged (the server's rejection count lags by up to a
//                ServerStats period);
//   - round trip: the network round trip's p99 (echoes, injected delay excluded) above the
//                scheme's tolerance (round_trip_tolerance_ms()), judged over at least
//                min_echoes echoes;
//   - rejected:  the server rejected more commands (outside the workspace, non-finite, stale,
//                ...) than it accepted from this master: the slave mostly held still;
//   - driver:    the device fell silent (no valid reading past the master's driver timeout) at
//                least once: part of the session had no operator and the slave held.
// The session verdict is the loop's (SessionMetrics) when that is worse than stable, else
// "degraded" when any of the above holds, else "stable"; each maps to its exit status
// (common/util/exit_codes.hpp).
#include <algorithm>
#include <cstdint>
#include <string>

#include "client/metrics/session_metrics.hpp"

namespace teleop::master {

/// What the master counted of its commands and their echoes.
struct LinkCounts {
  std::uint64_t issued = 0;           ///< commands the loop issued (into the forward channel)
  std::uint64_t in_flight = 0;        ///< of them, still held in the injected delay at the end
  std::uint64_t received = 0;         ///< accepted by the server from this master
  std::uint64_t rejected = 0;         ///< rejected by the server during the session (any sender)
  double rtt_p99_ms = 0.0;            ///< network round trip p99 [ms] (NaN: no echo)
  std::uint64_t echoes = 0;           ///< echoes behind rtt_p99_ms
  std::uint64_t driver_silences = 0;  ///< times the device fell silent past the timeout
  double driver_silent_s = 0.0;       ///< time silent in all [s]
};

/// The thresholds (see the file comment).
struct LinkTolerance {
  double max_lost_fraction = 0.05;  ///< lost / (issued - in_flight) above this is degraded
  double round_trip_ms = 50.0;      ///< network round trip p99 above this is degraded [ms]
  std::uint64_t min_echoes = 100;   ///< fewer echoes: the round trip is not judged
};

/// The network round trip p99 a scheme tolerates [ms]: 500 for a scheme passive at any delay
/// by design (SchemeTraits::passive_by_design), else 50. @throws ConfigError naming the
/// allowed schemes if `scheme` is unknown.
double round_trip_tolerance_ms(const std::string& scheme);
/// The tolerance of `scheme` with the default loss threshold.
LinkTolerance link_tolerance(const std::string& scheme);

/// Commands lost: issued, not in flight, never accepted by the server (the summary's "lost").
inline std::uint64_t lost_commands(const LinkCounts& c) {
  const std::uint64_t left = c.issued - std::min(c.in_flight, c.issued);
  return left - std::min(c.received, left);
}

/// The link's judgement: degraded or not, and why.
struct LinkJudgement {
  bool degraded = false;
  std::string reason;  ///< "" when not degraded; else each cause with its figures and bound
};
LinkJudgement judge_link(const LinkCounts& counts, const LinkTolerance& tolerance);

/// A session's verdict name and its reason from the loop's verdict and the link's judgement
/// (see the file comment).
struct SessionVerdict {
  std::string name;  ///< "stable" | "degraded" | "oscillating" | "out-of-spec" | "unstable"
  std::string reason;
  int exit_status = 0;  ///< common/util/exit_codes.hpp
};
SessionVerdict combine_verdict(Verdict loop, const std::string& loop_reason,
                               const LinkJudgement& link);

}  // namespace teleop::master
