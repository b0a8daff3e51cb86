// The loop delay: a command's entry time to the cycle that uses its echo, each echo counted
// once, stale and out-of-range echoes ignored, and no allocation per cycle.
#include "client/node/loop_delay_meter.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/support/alloc_counter.hpp"

namespace teleop::master {
namespace {

TEST(LoopDelayMeter, TheDelayRunsFromTheEntryToTheCycleThatUsesTheEcho) {
  LoopDelayMeter m;
  EXPECT_TRUE(std::isnan(m.last_ms()));
  m.entered(1, 10.000);
  m.entered(2, 10.001);
  m.entered(3, 10.002);
  EXPECT_TRUE(m.echo_used(1, 3, 10.0045));
  EXPECT_NEAR(m.last_ms(), 4.5, 1e-9);
  // the same echo again (no newer state arrived) is not a new delay
  EXPECT_FALSE(m.echo_used(1, 3, 10.0050));
  EXPECT_NEAR(m.last_ms(), 4.5, 1e-9);
  // an older echo after a newer one is ignored
  EXPECT_TRUE(m.echo_used(2, 3, 10.0060));
  EXPECT_NEAR(m.last_ms(), 5.0, 1e-9);
  EXPECT_FALSE(m.echo_used(1, 3, 10.0070));
  const Summary s = m.summary();
  EXPECT_EQ(s.count, 2u);
  EXPECT_NEAR(s.max, 5.0, 1e-9);
}

TEST(LoopDelayMeter, EchoesOfTheNewestCommandOrOlderThanTheRingAreIgnored) {
  LoopDelayMeter m;
  m.entered(5, 1.0);
  EXPECT_FALSE(m.echo_used(5, 5, 1.001)) << "the newest command cannot have been echoed yet";
  EXPECT_FALSE(m.echo_used(0, 5, 1.001)) << "seq 0: no command";
  // an echo whose entry slot has been written again by a newer command
  const std::uint64_t newest = 10 + LoopDelayMeter::kEntryRing;
  EXPECT_FALSE(m.echo_used(10, newest, 2.0));
  EXPECT_TRUE(m.echo_used(11, newest, 2.0));
  EXPECT_EQ(m.summary().count, 1u);
}

TEST(LoopDelayMeter, ACycleAllocatesNothing) {
  LoopDelayMeter m;
  test::NoAllocScope scope;
  for (std::uint64_t seq = 1; seq < 5000; ++seq) {
    const double now = 1e-3 * static_cast<double>(seq);
    m.entered(seq, now);
    if (seq > 3) m.echo_used(seq - 3, seq, now);
  }
  EXPECT_EQ(scope.allocations(), 0u);
}

}  // namespace
}  // namespace teleop::master
