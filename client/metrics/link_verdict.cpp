#include "client/metrics/link_verdict.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "client/control/scheme_traits.hpp"
#include "common/util/exit_codes.hpp"

namespace teleop::master {

double round_trip_tolerance_ms(const std::string& scheme) {
  return scheme_traits(scheme).passive_by_design ? 500.0 : 50.0;
}

LinkTolerance link_tolerance(const std::string& scheme) {
  LinkTolerance t;
  t.round_trip_ms = round_trip_tolerance_ms(scheme);
  return t;
}

LinkJudgement judge_link(const LinkCounts& c, const LinkTolerance& t) {
  LinkJudgement j;
  char buf[200];
  auto add = [&j](const char* cause) {
    j.reason += (j.reason.empty() ? "" : "; ") + std::string(cause);
    j.degraded = true;
  };
  const std::uint64_t left = c.issued - std::min(c.in_flight, c.issued);
  const bool mostly_rejected = c.rejected > 0 && c.rejected > c.received;
  // rejected commands reached the server: only the rest were lost on the way
  const std::uint64_t lost = lost_commands(c) - std::min(lost_commands(c), c.rejected);
  if (!mostly_rejected && left > 0 &&
      static_cast<double>(lost) > t.max_lost_fraction * static_cast<double>(left)) {
    std::snprintf(buf, sizeof(buf), "%llu of %llu commands lost (%.1f %%, more than %.3g %%)",
                  static_cast<unsigned long long>(lost), static_cast<unsigned long long>(left),
                  100.0 * static_cast<double>(lost) / static_cast<double>(left),
                  100.0 * t.max_lost_fraction);
    add(buf);
  }
  if (c.echoes >= t.min_echoes && std::isfinite(c.rtt_p99_ms) && c.rtt_p99_ms > t.round_trip_ms) {
    std::snprintf(buf, sizeof(buf),
                  "round trip p99 %.1f ms above the scheme's tolerance of %.0f ms", c.rtt_p99_ms,
                  t.round_trip_ms);
    add(buf);
  }
  if (mostly_rejected) {
    std::snprintf(
        buf, sizeof(buf), "the server rejected %llu commands and accepted %llu of this master's",
        static_cast<unsigned long long>(c.rejected), static_cast<unsigned long long>(c.received));
    add(buf);
  }
  if (c.driver_silences > 0) {
    std::snprintf(buf, sizeof(buf),
                  "the device fell silent %llu times (%.2f s in all): the slave held meanwhile",
                  static_cast<unsigned long long>(c.driver_silences), c.driver_silent_s);
    add(buf);
  }
  return j;
}

SessionVerdict combine_verdict(Verdict loop, const std::string& loop_reason,
                               const LinkJudgement& link) {
  SessionVerdict v;
  v.name = verdict_name(loop);
  v.reason = loop_reason;
  switch (loop) {
    case Verdict::kStable:
      v.exit_status = exit_code::kOk;
      break;
    case Verdict::kOscillating:
      v.exit_status = exit_code::kOscillating;
      break;
    case Verdict::kOutOfSpec:
      v.exit_status = exit_code::kOutOfSpec;
      break;
    case Verdict::kUnstable:
      v.exit_status = exit_code::kUnstable;
      break;
  }
  if (!link.degraded) return v;
  if (loop == Verdict::kStable) {
    v.name = "degraded";
    v.reason = link.reason;
    v.exit_status = exit_code::kDegraded;
  } else {
    v.reason += (v.reason.empty() ? "" : "; ") + std::string("link degraded: ") + link.reason;
  }
  return v;
}

}  // namespace teleop::master
