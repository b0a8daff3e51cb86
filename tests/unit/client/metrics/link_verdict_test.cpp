// The link's part of the session verdict (client/metrics/link_verdict.hpp).
#include "client/metrics/link_verdict.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "client/control/bilateral_controller.hpp"
#include "client/control/scheme_traits.hpp"
#include "common/util/exit_codes.hpp"
#include "tests/support/config_error.hpp"

namespace {

using teleop::master::combine_verdict;
using teleop::master::judge_link;
using teleop::master::link_tolerance;
using teleop::master::LinkCounts;
using teleop::master::lost_commands;
using teleop::master::round_trip_tolerance_ms;
using teleop::master::Verdict;

/// 10,000 commands, all received, a loopback round trip.
LinkCounts healthy() {
  LinkCounts c;
  c.issued = 10000;
  c.received = 10000;
  c.rtt_p99_ms = 0.4;
  c.echoes = 9000;
  return c;
}

TEST(LinkVerdict, CommandsInFlightAtTheEndAreNotLost) {
  LinkCounts c = healthy();
  c.received = 9950;
  c.in_flight = 50;  // 50 ms of injected delay at 1 kHz when the master stopped
  EXPECT_EQ(lost_commands(c), 0u);
  EXPECT_FALSE(judge_link(c, link_tolerance("position-position")).degraded);
  c.received = 9900;
  EXPECT_EQ(lost_commands(c), 50u);
  c.in_flight = 20000;  // never more in flight than issued
  EXPECT_EQ(lost_commands(c), 0u);
}

TEST(LinkVerdict, LossBeyondTheThresholdIsDegraded) {
  LinkCounts c = healthy();
  c.received = 9500;  // 5 %: at the bound, still carried
  EXPECT_FALSE(judge_link(c, link_tolerance("position-position")).degraded);
  c.received = 7600;  // 24 % lost
  const auto j = judge_link(c, link_tolerance("position-position"));
  EXPECT_TRUE(j.degraded);
  EXPECT_NE(j.reason.find("2400 of 10000 commands lost"), std::string::npos) << j.reason;
  EXPECT_NE(j.reason.find("more than 5 %"), std::string::npos) << j.reason;
}

TEST(LinkVerdict, TheRoundTripToleranceFollowsTheSchemesPassivity) {
  for (const std::string& name : teleop::master::controller_names()) {
    const double want = teleop::master::scheme_traits(name).passive_by_design ? 500.0 : 50.0;
    EXPECT_EQ(round_trip_tolerance_ms(name), want) << name;
    EXPECT_EQ(link_tolerance(name).round_trip_ms, want) << name;
  }
  EXPECT_NE(
      teleop::test::config_error_of([] { link_tolerance("pp"); }).find("scheme 'pp' is unknown"),
      std::string::npos);
}

TEST(LinkVerdict, RoundTripBeyondTheSchemesToleranceIsDegraded) {
  LinkCounts c = healthy();
  c.rtt_p99_ms = 2600.0;
  auto j = judge_link(c, link_tolerance("position-position"));
  EXPECT_TRUE(j.degraded);
  EXPECT_NE(j.reason.find("round trip p99 2600.0 ms above the scheme's tolerance of 50 ms"),
            std::string::npos)
      << j.reason;
  c.rtt_p99_ms = 200.0;  // too slow for position-position, fine for a passive scheme
  EXPECT_TRUE(judge_link(c, link_tolerance("force-position")).degraded);
  EXPECT_FALSE(judge_link(c, link_tolerance("wave-variables")).degraded);
  EXPECT_FALSE(judge_link(c, link_tolerance("tdpa")).degraded);
  EXPECT_FALSE(judge_link(c, link_tolerance("model-mediated")).degraded);
  c.echoes = 10;  // too few echoes to judge a p99
  EXPECT_FALSE(judge_link(c, link_tolerance("position-position")).degraded);
  c.echoes = 9000;
  c.rtt_p99_ms = std::nan("");  // no echo at all: nothing to judge here (the loss says it)
  EXPECT_FALSE(judge_link(c, link_tolerance("position-position")).degraded);
}

TEST(LinkVerdict, MostlyRejectedCommandsAreDegraded) {
  // a contact point out of the workspace: the server takes few commands and rejects the rest
  LinkCounts c = healthy();
  c.received = 93;
  c.rejected = 4561;
  c.issued = 5140;
  auto j = judge_link(c, link_tolerance("tdpa"));
  EXPECT_TRUE(j.degraded);
  EXPECT_EQ(j.reason, "the server rejected 4561 commands and accepted 93 of this master's");
  // fewer rejected than accepted (a flood of a third party's bad samples): not most
  c = healthy();
  c.rejected = 3000;
  EXPECT_FALSE(judge_link(c, link_tolerance("tdpa")).degraded);
}

TEST(LinkVerdict, RejectedCommandsAreNotLostOnTheWay) {
  LinkCounts c = healthy();
  c.received = 6000;
  c.rejected = 3900;  // 4000 not accepted, 3900 of them rejected: 100 (1 %) lost on the way
  EXPECT_FALSE(judge_link(c, link_tolerance("position-position")).degraded);
  c.rejected = 3000;  // 1000 (10 %) lost on the way
  EXPECT_NE(judge_link(c, link_tolerance("position-position")).reason.find("1000 of 10000"),
            std::string::npos);
}

TEST(LinkVerdict, EveryCauseIsNamed) {
  LinkCounts c = healthy();
  c.received = 5000;
  c.rtt_p99_ms = 80.0;
  auto j = judge_link(c, link_tolerance("position-position"));
  EXPECT_EQ(j.reason,
            "5000 of 10000 commands lost (50.0 %, more than 5 %); round trip p99 80.0 ms above "
            "the scheme's tolerance of 50 ms");
  c.rejected = 6000;
  j = judge_link(c, link_tolerance("position-position"));
  EXPECT_EQ(j.reason,
            "round trip p99 80.0 ms above the scheme's tolerance of 50 ms; the server rejected "
            "6000 commands and accepted 5000 of this master's");
}

TEST(SessionVerdict, EachVerdictHasItsExitStatus) {
  namespace code = teleop::exit_code;
  const teleop::master::LinkJudgement ok;
  teleop::master::LinkJudgement bad;
  bad.degraded = true;
  bad.reason = "2400 of 10000 commands lost";
  auto v = combine_verdict(Verdict::kStable, "", ok);
  EXPECT_EQ(v.name, "stable");
  EXPECT_EQ(v.exit_status, code::kOk);
  v = combine_verdict(Verdict::kStable, "", bad);
  EXPECT_EQ(v.name, "degraded");
  EXPECT_EQ(v.reason, bad.reason);
  EXPECT_EQ(v.exit_status, code::kDegraded);
  v = combine_verdict(Verdict::kOscillating, "sustained oscillation", ok);
  EXPECT_EQ(v.exit_status, code::kOscillating);
  v = combine_verdict(Verdict::kOutOfSpec, "force above the rating", ok);
  EXPECT_EQ(v.exit_status, code::kOutOfSpec);
  // a worse loop verdict stands, and the link's trouble is added to its reason
  v = combine_verdict(Verdict::kUnstable, "force at the limit too long", bad);
  EXPECT_EQ(v.name, "unstable");
  EXPECT_EQ(v.exit_status, code::kUnstable);
  EXPECT_EQ(v.reason, "force at the limit too long; link degraded: 2400 of 10000 commands lost");
  // every code is distinct and none is a success but stable's
  const int codes[] = {code::kFailure,  code::kUsage,       code::kNoPeer,    code::kRefused,
                       code::kDegraded, code::kOscillating, code::kOutOfSpec, code::kUnstable};
  for (std::size_t i = 0; i < std::size(codes); ++i) {
    EXPECT_NE(codes[i], code::kOk);
    for (std::size_t k = i + 1; k < std::size(codes); ++k) EXPECT_NE(codes[i], codes[k]);
  }
}

}  // namespace
