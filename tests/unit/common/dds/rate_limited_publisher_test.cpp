// RateLimitedPublisher: the loop's offer() allocates nothing, the copies come out at about their
// rate whatever the offer rate, a rate-0 output writes what is offered with wake, and a late
// reader gets the next copy within a period.
#include "common/dds/rate_limited_publisher.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "common/util/clock.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"
#include "tests/support/alloc_counter.hpp"
#include "tests/support/domains.hpp"

namespace teleop::dds {
namespace {

using Info = eprosima::fastdds::dds::SampleInfo;

// the tests' own topics, with the QoS class of the observer copies and of the stats
constexpr Topic<SlaveStatePubSubType> kStateFast{"test/state_fast", TopicQos::kLatest};
constexpr Topic<SlaveStatePubSubType> kStateSlow{"test/state_slow", TopicQos::kLatest};
constexpr Topic<ServerStatsPubSubType> kStats{"test/stats", TopicQos::kReliableStream};

SlaveState robot_state(std::uint64_t seq) {
  SlaveState s;
  s.seq(seq);
  s.joint_position_rad().assign(6, 0.1);
  s.joint_velocity_radps().assign(6, 0.0);
  s.joint_torque_nm().assign(6, 0.0);
  return s;
}

TEST(RateLimitedPublisher, OfferAllocatesNothingAndCopiesComeAtTheirRate) {
  Participant p(ParticipantOptions{"loopback", test::domains::kRateLimitedUnit, "rlp"});
  RateLimitedPublisher<SlaveStatePubSubType> pub(p, {{kStateFast, 50.0}, {kStateSlow, 5.0}});
  std::atomic<std::uint64_t> fast{0}, slow{0}, newest_slow{0};
  Reader<SlaveStatePubSubType> r_fast(p, kStateFast,
                                      [&](const SlaveState&, const Info&) { fast.fetch_add(1); });
  Reader<SlaveStatePubSubType> r_slow(p, kStateSlow, [&](const SlaveState& s, const Info&) {
    slow.fetch_add(1);
    newest_slow.store(s.seq());
  });
  SlaveState s = robot_state(1);
  pub.offer(s);  // warm-up: the slot's sequences get their size
  const auto t0 = now_ns();
  while (seconds_between(t0, now_ns()) < 10.0 && (pub.matched(0) < 1 || pub.matched(1) < 1)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_EQ(pub.matched(0), 1);
  ASSERT_EQ(pub.matched(1), 1);
  const std::uint64_t fast0 = fast.load(), slow0 = slow.load();
  const auto t1 = now_ns();
  std::uint64_t allocations = 0;
  for (std::uint64_t i = 2; seconds_between(t1, now_ns()) < 1.5; ++i) {  // a 1 kHz "loop"
    s.seq(i);
    {
      test::NoAllocScope scope;
      pub.offer(s);
      allocations += scope.allocations();
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  const double elapsed = seconds_between(t1, now_ns());
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ(allocations, 0u);
  const double fast_hz = static_cast<double>(fast.load() - fast0) / elapsed;
  const double slow_hz = static_cast<double>(slow.load() - slow0) / elapsed;
  // generous bounds: the rates, not the 1 kHz offers
  EXPECT_GT(fast_hz, 20.0);
  EXPECT_LT(fast_hz, 80.0);
  EXPECT_GT(slow_hz, 1.5);
  EXPECT_LT(slow_hz, 10.0);
  EXPECT_GT(newest_slow.load(), 1000u);  // recent samples, not the first ones

  // a late reader: Fast DDS 2.9's best-effort writer keeps no history for it (why kLatest is
  // volatile); it gets the next copy within one period once the loop offers again
  std::atomic<std::uint64_t> late_seq{0};
  Reader<SlaveStatePubSubType> late(
      p, kStateSlow, [&](const SlaveState& x, const Info&) { late_seq.store(x.seq()); });
  const auto t_match = now_ns();
  while (seconds_between(t_match, now_ns()) < 10.0 && pub.matched(1) < 2) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ASSERT_EQ(pub.matched(1), 2);
  s.seq(s.seq() + 1);
  pub.offer(s);
  const auto t_late = now_ns();
  while (seconds_between(t_late, now_ns()) < 5.0 && late_seq.load() == 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  EXPECT_EQ(late_seq.load(), s.seq());
  EXPECT_LT(seconds_between(t_late, now_ns()), 1.0);  // one 5 Hz period is 0.2 s
}

TEST(RateLimitedPublisher, RateZeroWritesWhatIsOfferedWithWake) {
  Participant p(ParticipantOptions{"loopback", test::domains::kRateLimitedUnit + 1, "rlp0"});
  RateLimitedPublisher<ServerStatsPubSubType> pub(p, {{kStats, 0.0}});
  std::atomic<std::uint64_t> got{0}, last_steps{0};
  Reader<ServerStatsPubSubType> r(p, kStats, [&](const ServerStats& st, const Info&) {
    got.fetch_add(1);
    last_steps.store(st.steps());
  });
  const auto t0 = now_ns();
  while (seconds_between(t0, now_ns()) < 10.0 && pub.matched(0) < 1) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ServerStats st;
  for (std::uint64_t i = 1; i <= 5; ++i) {
    st.steps(i);
    pub.offer(st, /*wake=*/true);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  const auto t1 = now_ns();
  while (seconds_between(t1, now_ns()) < 5.0 && last_steps.load() != 5) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_EQ(last_steps.load(), 5u);
  EXPECT_GE(got.load(), 4u);  // one per offer; a rare one may be skipped under the try-lock
}

TEST(RateLimitedPublisher, RejectsANegativeRate) {
  Participant p(ParticipantOptions{"loopback", test::domains::kRateLimitedUnit + 2, "rlpbad"});
  try {
    RateLimitedPublisher<SlaveStatePubSubType> pub(p, {{{"test/bad", TopicQos::kLatest}, -1.0}});
    FAIL() << "no error";
  } catch (const DdsError& e) {
    EXPECT_NE(std::string(e.what()).find("test/bad"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("[0, 1e4]"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace teleop::dds
