// The one writer of teleop/events (common/dds/event_publisher.hpp): what a reader gets is the
// event's kind, severity, value, message and tags, with the program's name, numbered in order;
// a message past the IDL's bound is cut, not refused; publishing allocates nothing.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "common/dds/endpoint.hpp"
#include "common/dds/event_publisher.hpp"
#include "common/util/clock.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/support/domains.hpp"

namespace teleop::dds {
namespace {

/// The events a reader on teleop/events received, in order.
struct Received {
  std::mutex m;
  std::vector<Event> events;

  /// Waits up to 10 s for `n` events; a copy of what came.
  std::vector<Event> wait_for(std::size_t n) {
    const auto t0 = now_ns();
    for (;;) {
      {
        std::lock_guard<std::mutex> lock(m);
        if (events.size() >= n || seconds_between(t0, now_ns()) > 10.0) return events;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }
};

/// Publishes a clamped K_ps (a SimEvent with its subject and session) and a refusal whose
/// message is past the IDL's bound, counting the allocations of both publishes.
std::uint64_t publish_two(EventPublisher& events) {
  sim::SimEvent clamp;
  clamp.kind = sim::EventKind::kLimit;
  clamp.severity = sim::Severity::kWarning;
  clamp.value = 9.5e5;
  clamp.tags.session = 0x1234u;
  clamp.tags.subject = sim::EventSubject::kPositionGain;
  std::snprintf(clamp.message, sizeof(clamp.message), "K_ps clamped");
  const std::string long_text(300, 'x');
  sim::EventTags refusal;
  refusal.session = 0xbu;
  refusal.other_session = 0xau;
  test::NoAllocScope count;  // both publishes: copies into primed buffers
  events.publish(clamp);
  events.publish(sim::EventKind::kOwnership, sim::Severity::kWarning, long_text.c_str(), 2.0,
                 refusal);
  return count.allocations();
}

TEST(EventPublisher, AReaderGetsTheFieldsTheTagsAndTheOrder) {
  Participant p(ParticipantOptions{"loopback", test::domains::kEventPublisherUnit, "events"});
  Received received;
  Reader<EventPubSubType> reader(p, topics::kEvents,
                                 [&](const Event& e, const eprosima::fastdds::dds::SampleInfo&) {
                                   std::lock_guard<std::mutex> lock(received.m);
                                   received.events.push_back(e);
                                 });
  EventPublisher events(p, "server");
  const auto t0 = now_ns();
  while (reader.matched() < 1 && seconds_between(t0, now_ns()) < 10.0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_EQ(reader.matched(), 1);
  EXPECT_EQ(publish_two(events), 0u);
  EXPECT_TRUE(events.flush(5.0));
  const std::vector<Event> got = received.wait_for(2);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].source(), "server");
  EXPECT_EQ(got[0].seq(), 1u);
  EXPECT_EQ(got[1].seq(), 2u);
  EXPECT_EQ(got[0].kind(), EVENT_LIMIT);
  EXPECT_EQ(got[0].subject(), EVENT_SUBJECT_POSITION_GAIN);
  EXPECT_EQ(got[0].session(), 0x1234u);
  EXPECT_EQ(got[0].other_session(), 0u);
  EXPECT_EQ(got[0].severity(), 1u);
  EXPECT_DOUBLE_EQ(got[0].value(), 9.5e5);
  EXPECT_EQ(got[0].message(), "K_ps clamped");
  EXPECT_EQ(got[1].kind(), EVENT_OWNERSHIP);
  EXPECT_EQ(got[1].subject(), EVENT_SUBJECT_NONE);
  EXPECT_EQ(got[1].session(), 0xbu);
  EXPECT_EQ(got[1].other_session(), 0xau);
  EXPECT_EQ(got[1].message().size(), EventPublisher::kMessageBound);  // cut to the IDL's bound
  EXPECT_EQ(events.published(), 2u);
  EXPECT_EQ(events.failures(), 0u);
  EXPECT_EQ(events.dropped(), 0u);
}

}  // namespace
}  // namespace teleop::dds
