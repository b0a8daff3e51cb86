// The loops' writers hand samples to a network thread: write() never waits and does not
// allocate once primed; every sample is written or replaced by a newer one (counted), in
// hand-off order, and the newest always goes out.
#include "common/dds/async_writer.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

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
      p, topics::kMasterCommand,
      [&](const MasterCommand& c, const eprosima::fastdds::dds::SampleInfo&) {
        newest.store(c.seq());
      });
  LatestWriter<MasterCommandPubSubType> writer(p, topics::kMasterCommand);
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

TEST(QueuedWriter, SamplesGoOutInOrderAndTheNewestIsNeverTheOneDropped) {
  Participant p(ParticipantOptions{"loopback", test::domains::kAsyncWriterUnit + 1, "queued"});
  std::mutex m;
  std::vector<std::uint64_t> seen;
  Reader<MasterCommandPubSubType> reader(
      p, topics::kMasterCommand,
      [&](const MasterCommand& c, const eprosima::fastdds::dds::SampleInfo&) {
        std::lock_guard<std::mutex> lock(m);
        seen.push_back(c.seq());
      });
  QueuedWriter<MasterCommandPubSubType, 4> writer(p, topics::kMasterCommand);
  MasterCommand c;
  c.master_name(std::string(40, 'n'));
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
  EXPECT_EQ(writer.written() + writer.dropped(), writer.handed());
  EXPECT_EQ(writer.failures(), 0u);
  for (int k = 0; k < 200; ++k) {
    {
      std::lock_guard<std::mutex> lock(m);
      if (!seen.empty() && seen.back() == kSamples) break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  std::lock_guard<std::mutex> lock(m);
  ASSERT_FALSE(seen.empty());
  EXPECT_EQ(seen.back(), static_cast<std::uint64_t>(kSamples));  // the newest always goes out
  for (std::size_t i = 1; i < seen.size(); ++i) {
    ASSERT_LT(seen[i - 1], seen[i]) << "out of order at " << i;  // in hand-off order
  }
}

TEST(QueuedWriter, EveryEventGoesOutWhenTheThreadKeepsUp) {
  Participant p(ParticipantOptions{"loopback", test::domains::kAsyncWriterUnit + 1, "events"});
  QueuedWriter<EventPubSubType, 8> writer(p, topics::kEvents);
  Event e;
  e.source(std::string(32, 's'));
  e.message(std::string(256, 'm'));
  writer.prime(e);
  std::uint64_t allocations = 0;
  for (int k = 1; k <= 50; ++k) {
    e.seq(static_cast<std::uint64_t>(k));
    test::NoAllocScope scope;
    writer.write(e);
    allocations += scope.allocations();
    ASSERT_TRUE(writer.flush(5.0));  // the thread keeps up: nothing is replaced
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(writer.dropped(), 0u);
  EXPECT_EQ(writer.written(), 50u);
}

}  // namespace
}  // namespace teleop::dds
