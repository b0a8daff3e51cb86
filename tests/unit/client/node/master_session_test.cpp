// The master's session bookkeeping (client/node/master_session.hpp), driven by a fake clock: the
// plan from the options, when the loop is over, the cycles that publish MasterState, the server's
// faults, link losses, stalls and ownership in the report, and no allocation per cycle.
#include "client/node/master_session.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>

#include "client/device/operator_model.hpp"
#include "client/node/master_node.hpp"
#include "client/node/master_report.hpp"
#include "tests/support/alloc_counter.hpp"

namespace teleop::master {
namespace {

constexpr std::int64_t kT0Ns = 40'000'000'000;  // the loop's start on a steady clock [ns]
constexpr double kT0 = 40.0;                    // the same [s]
constexpr double kNoSession = -1.0;             // MasterCycle::session_start_s() while homing

SessionPlan plan(double length_s, std::uint64_t samples = 0) {
  SessionPlan p;
  p.samples = samples;
  p.state_every = 10;
  p.session_length_s = length_s;
  p.grace_s = 0.5;
  p.wait_owner_s = 0.0;
  return p;
}

TEST(MasterSession, ThePlanFollowsTheOptions) {
  MasterOptions o;
  o.rate_hz = 1000.0;
  o.state_rate_hz = 100.0;
  o.duration_s = 7.0;
  o.forward.delay_s = 0.05;
  o.backward.delay_s = 0.1;
  o.samples = 123;
  o.wait_owner_s = 4.0;
  SessionPlan p = plan_session(o);
  EXPECT_EQ(p.state_every, 10u);
  EXPECT_EQ(p.session_length_s, 7.0);
  EXPECT_NEAR(p.grace_s, 0.5 + 2.0 * 0.15, 1e-12);
  EXPECT_EQ(p.samples, 123u);
  EXPECT_EQ(p.wait_owner_s, 4.0);
  // no duration: a simulated device runs its script and 1 s more, any other device 10 s
  o.duration_s = 0.0;
  o.device = "simulated";
  o.script = "press-slip";
  const double script_s = script_duration_s(press_slip_script(Eigen::Vector3d::Zero(), 0.02));
  EXPECT_NEAR(plan_session(o).session_length_s, std::max(2.0, script_s + 1.0), 1e-12);
  o.device = "external";
  EXPECT_EQ(plan_session(o).session_length_s, 10.0);
  // MasterState at least once a cycle, even when asked for more often than the loop runs
  o.state_rate_hz = 5000.0;
  EXPECT_EQ(plan_session(o).state_every, 1u);
}

TEST(MasterSession, TheLoopIsOverAfterHomingAndTheSessionLengthOrTheSampleLimit) {
  MasterSession s(plan(2.0), kT0Ns);
  EXPECT_EQ(s.t0_s(), kT0);
  EXPECT_FALSE(s.over(kT0 + 100.0, true, kNoSession)) << "homing never ends the loop";
  const double start = kT0 + 1.5;  // homing took 1.5 s
  EXPECT_FALSE(s.over(start + 1.999, false, start));
  EXPECT_TRUE(s.over(start + 2.0, false, start));

  MasterSession limited(plan(2.0, 3), kT0Ns);
  for (int k = 0; k < 3; ++k) {
    EXPECT_FALSE(limited.over(kT0, true, kNoSession));
    limited.begin_cycle(kT0 + 0.001 * k);
  }
  EXPECT_TRUE(limited.over(kT0, true, kNoSession)) << "the sample limit ends it while homing too";
}

TEST(MasterSession, ARefusalWithoutAWaitEndsTheLoop) {
  MasterSession s(plan(10.0), kT0Ns);
  EXPECT_EQ(s.owner().update(DdsSlaveLink::Owner::kOther, kT0 + 0.6),
            OwnershipWatch::Change::kRefused);
  EXPECT_TRUE(s.over(kT0 + 0.6, true, kNoSession));
  SessionReport rep;
  s.report(kT0 + 1.0, kNoSession, rep);
  EXPECT_TRUE(rep.refused);
  EXPECT_TRUE(rep.refused_first);
  EXPECT_NEAR(rep.waited_for_owner_s, 0.4, 1e-9);
  EXPECT_EQ(rep.session_s, 0.0) << "the session never began";
  EXPECT_NEAR(rep.elapsed_s, 1.0, 1e-9);
}

TEST(MasterSession, StateEveryNthCycleFaultsWhenTheyRiseAndLinkLossesWhenTheyBegin) {
  MasterSession s(plan(10.0), kT0Ns);
  int states = 0;
  int unstable = 0;
  const std::uint64_t faults[] = {0, 0, 2, 2, 2, 3, 3};
  const bool lost[] = {false, true, true, false, true, true, false};
  for (int k = 0; k < 7; ++k) {
    s.begin_cycle(kT0 + 0.001 * k);
    if (s.faults_rose(faults[k])) ++unstable;
    s.link_state(lost[k]);
  }
  EXPECT_EQ(unstable, 2);
  EXPECT_EQ(s.link_losses(), 2u);
  for (int k = 7; k < 30; ++k) {
    s.begin_cycle(kT0 + 0.001 * k);
    if (s.state_due()) ++states;
  }
  EXPECT_EQ(s.cycles(), 30u);
  EXPECT_EQ(states, 3) << "cycles 10, 20 and 30";
}

TEST(MasterSession, StallsAndTheLoopDelayGoIntoTheReport) {
  MasterSession s(plan(1.0), kT0Ns);
  double t = kT0;
  for (std::uint64_t seq = 1; seq <= 100; ++seq, t += 0.001) {
    EXPECT_EQ(s.begin_cycle(t), 0.0);
    s.loop_delay().entered(seq, t);
    if (seq > 4) s.loop_delay().echo_used(seq - 4, seq, t);
  }
  t += 0.3;  // the process was stopped
  EXPECT_NEAR(s.begin_cycle(t), 0.301, 1e-9);
  SessionReport rep;
  s.report(t + 0.5, kT0 + 0.05, rep);
  EXPECT_EQ(rep.stalls, 1u);
  EXPECT_NEAR(rep.longest_stall_s, 0.301, 1e-9);
  EXPECT_EQ(rep.loop_delay_ms.count, 96u);
  EXPECT_NEAR(rep.loop_delay_ms.max, 4.0, 1e-6);
  EXPECT_NEAR(rep.session_s, t + 0.5 - (kT0 + 0.05), 1e-9);
  EXPECT_FALSE(rep.refused);
  EXPECT_EQ(rep.link_losses, 0u);
}

TEST(MasterSession, ACycleAllocatesNothing) {
  MasterSession s(plan(1000.0), kT0Ns);
  test::NoAllocScope scope;
  double t = kT0;
  for (std::uint64_t seq = 1; seq < 5000; ++seq, t += 0.001) {
    if (s.over(t, seq < 1500, kT0 + 1.5)) break;
    s.begin_cycle(t);
    s.loop_delay().entered(seq, t);
    if (seq > 3) s.loop_delay().echo_used(seq - 3, seq, t);
    s.owner().update(DdsSlaveLink::Owner::kMine, t);
    s.faults_rose(seq / 1000);
    s.link_state(seq % 700 < 10);
    (void)s.state_due();
  }
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(s.cycles(), 4999u);
}

}  // namespace
}  // namespace teleop::master
