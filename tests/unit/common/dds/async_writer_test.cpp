// The loops' writers hand samples to a network thread: write() never waits and does not
// allocate once primed; every sample is written, replaced by a newer one (LatestWriter) or
// dropped when the ring is full (QueuedWriter), and counted.
#include "common/dds/async_writer.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <string>
#include <thread>

#include "teleop/idl/TeleopPubSubTypes.h"
#include "tests/support/alloc_counter.hpp"
#include "tests/support/domains.hpp"

namespace teleop::dds {
namespace {

TEST(TripleBuffer, TheConsumerTakesTheNewestAndReplacementsAreReported) {
  TripleBuffer<int> b;
  EXPECT_EQ(b.take(), nullptr);
  b.back() = 1;
  EXPECT_FALSE(b.publish());
  b.back() = 2;
  EXPECT_TRUE(b.publish());  // 1 was never taken
  int* v = b.take();
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(*v, 2);
  EXPECT_EQ(b.take(), nullptr);  // nothing new
  b.back() = 3;
  EXPECT_FALSE(b.publish());
  v = b.take();
  ASSERT_NE(v, nullptr);
  EXPECT_EQ(*v, 3);
}

TEST(LatestWriter, WritesNeverAllocateAndEverySampleIsWrittenOrCountedAsReplaced) {
  Participant p(ParticipantOptions{"loopback", test::domains::kAsyncWriterUnit, "async"});
  std::atomic<std::uint64_t> newest{0};
  Reader<MasterCommandPubSubType> reader(
      p, topics::kMasterCommand, TopicQos::kStream,
      [&](const MasterCommand& c, const eprosima::fastdds::dds::SampleInfo&) {
        newest.store(c.seq());
      });
  LatestWriter<MasterCommandPubSubType> writer(p, topics::kMasterCommand, TopicQos::kStream);
  MasterCommand c;
  c.master_name(std::string(40, 'n'));  // beyond the small-string buffer: would allocate
  writer.prime(c);
  constexpr int kSamples = 5000;
  std::uint64_t allocations = 0;
  for (int k = 1; k <= kSamples; ++k) {
    c.seq(static_cast<std::uint64_t>(k));
    test::NoAllocScope scope;
    EXPECT_TRUE(writer.write(c));
    allocations += scope.allocations();
  }
  EXPECT_EQ(allocations, 0u);
  ASSERT_TRUE(writer.flush(5.0));
  EXPECT_EQ(writer.handed(), static_cast<std::uint64_t>(kSamples));
  EXPECT_EQ(writer.written() + writer.replaced(), writer.handed());
  EXPECT_EQ(writer.failures(), 0u);
  EXPECT_GT(writer.written(), 0u);
  // the newest sample is never the one replaced: it reaches the reader
  for (int k = 0; k < 200 && newest.load() != kSamples; ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(newest.load(), static_cast<std::uint64_t>(kSamples));
}

TEST(QueuedWriter, SamplesGoOutInOrderAndAFullRingDropsAndCounts) {
  Participant p(ParticipantOptions{"loopback", test::domains::kAsyncWriterUnit + 1, "queued"});
  QueuedWriter<EventPubSubType, 8> writer(p, topics::kEvents, TopicQos::kEventLog);
  Event e;
  e.source(std::string(32, 's'));
  e.message(std::string(256, 'm'));
  writer.prime(e);
  constexpr int kSamples = 2000;
  std::uint64_t allocations = 0, refused = 0;
  for (int k = 1; k <= kSamples; ++k) {
    e.seq(static_cast<std::uint64_t>(k));
    test::NoAllocScope scope;
    if (!writer.write(e)) ++refused;
    allocations += scope.allocations();
  }
  EXPECT_EQ(allocations, 0u);
  ASSERT_TRUE(writer.flush(5.0));
  EXPECT_EQ(writer.dropped(), refused);
  EXPECT_EQ(writer.written() + writer.dropped(), static_cast<std::uint64_t>(kSamples));
  EXPECT_EQ(writer.failures(), 0u);
}

}  // namespace
}  // namespace teleop::dds
