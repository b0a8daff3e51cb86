// Fast DDS's error lines are summarized: kinds ignore the numbers in a line, oversized samples
// are recognized and counted, and a flood of oversized samples from a hostile writer is
// counted (not a line each).
#include "common/dds/log_summary.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <thread>
#include <vector>

#include "common/dds/endpoint.hpp"
#include "common/util/clock.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"
#include "tests/support/domains.hpp"

namespace teleop::dds {
namespace {

TEST(LogSummary, KindsIgnoreNumbers) {
  const std::string a =
      "Change payload size of '5000' bytes is larger than the history payload "
      "size of '331' bytes and cannot be resized.";
  const std::string b =
      "Change payload size of '70' bytes is larger than the history payload "
      "size of '12' bytes and cannot be resized.";
  EXPECT_EQ(log_kind("RTPS_READER_HISTORY", a), log_kind("RTPS_READER_HISTORY", b));
  EXPECT_NE(log_kind("RTPS_READER_HISTORY", a), log_kind("OTHER", a));
  EXPECT_NE(log_kind("X", "no peer"), log_kind("X", "no peers"));
  EXPECT_EQ(log_kind("X", "port 7410"), "X|port #");
  EXPECT_TRUE(is_oversized_sample_line("RTPS_READER_HISTORY", a));
  EXPECT_FALSE(is_oversized_sample_line("RTPS_READER_HISTORY", "History full"));
  EXPECT_FALSE(is_oversized_sample_line("RTPS_WRITER", a));
}

/// Raw bytes written under MasterCommand's type name: a writer that ignores the type's bound.
struct Blob {
  std::vector<std::uint8_t> bytes;
};

class BlobType : public eprosima::fastdds::dds::TopicDataType {
 public:
  BlobType() {
    setName(MasterCommandPubSubType().getName());
    m_typeSize = 16384;
    m_isGetKeyDefined = false;
  }
  bool serialize(void* data, eprosima::fastrtps::rtps::SerializedPayload_t* payload) override {
    const auto& b = static_cast<Blob*>(data)->bytes;
    if (b.size() > payload->max_size) return false;
    std::memcpy(payload->data, b.data(), b.size());
    payload->length = static_cast<std::uint32_t>(b.size());
    return true;
  }
  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t*, void*) override { return false; }
  std::function<std::uint32_t()> getSerializedSizeProvider(void* data) override {
    return [data] { return static_cast<std::uint32_t>(static_cast<Blob*>(data)->bytes.size()); };
  }
  void* createData() override { return new Blob(); }
  void deleteData(void* data) override { delete static_cast<Blob*>(data); }
  bool getKey(void*, eprosima::fastrtps::rtps::InstanceHandle_t*, bool) override { return false; }
};

/// The reader has matched the writer and the writer the reader (a best-effort writer sends only
/// to the readers it has matched).
bool both_matched(const Reader<MasterCommandPubSubType>& reader,
                  eprosima::fastdds::dds::DataWriter* writer) {
  eprosima::fastdds::dds::PublicationMatchedStatus st;
  return reader.matched() >= 1 &&
         writer->get_publication_matched_status(st) == ReturnCode_t::RETCODE_OK &&
         st.current_count >= 1;
}

TEST(LogSummary, OversizedSamplesAreCounted) {
  const int domain = test::domains::kOversizedUnit;
  Participant p(ParticipantOptions{"loopback", domain, "oversized"});
  std::atomic<int> received{0};
  Reader<MasterCommandPubSubType> reader(
      p, Topic<MasterCommandPubSubType>{"test/oversized", TopicQos::kStream},
      [&](const MasterCommand&, const eprosima::fastdds::dds::SampleInfo&) { ++received; });
  Participant hostile(ParticipantOptions{"loopback", domain, "hostile"});
  auto* topic =
      hostile.topic("test/oversized", eprosima::fastdds::dds::TypeSupport(new BlobType()));
  auto* writer = hostile.publisher()->create_datawriter(
      topic, writer_qos(hostile.publisher(), TopicQos::kStream));
  ASSERT_NE(writer, nullptr);
  const auto t0 = now_ns();
  while (!both_matched(reader, writer) && seconds_between(t0, now_ns()) < 20.0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_TRUE(both_matched(reader, writer));
  const std::uint64_t before = oversized_samples();
  Blob big{std::vector<std::uint8_t>(8000, 0)};
  big.bytes[1] = 1;  // CDR little endian
  for (int i = 0; i < 50; ++i) {
    writer->write(&big);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  const auto t1 = now_ns();
  while (oversized_samples() - before < 50 && seconds_between(t1, now_ns()) < 3.0) {
    flush_log_summary();
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  // best effort: not every sample need arrive, but every one that did is counted, none delivered
  EXPECT_GE(oversized_samples() - before, 25u);
  EXPECT_LE(oversized_samples() - before, 50u);
  EXPECT_EQ(received.load(), 0);
  EXPECT_GE(fastdds_log_entries(), oversized_samples() - before);
  hostile.publisher()->delete_datawriter(writer);
}

TEST(LogSummary, MalformedSamplesAreCountedByTheReader) {
  const int domain = test::domains::kOversizedUnit + 2;
  Participant p(ParticipantOptions{"loopback", domain, "malformed"});
  std::atomic<int> received{0};
  Reader<MasterCommandPubSubType> reader(
      p, Topic<MasterCommandPubSubType>{"test/malformed", TopicQos::kStream},
      [&](const MasterCommand&, const eprosima::fastdds::dds::SampleInfo&) { ++received; });
  Participant hostile(ParticipantOptions{"loopback", domain, "hostile"});
  auto* topic =
      hostile.topic("test/malformed", eprosima::fastdds::dds::TypeSupport(new BlobType()));
  auto* writer = hostile.publisher()->create_datawriter(
      topic, writer_qos(hostile.publisher(), TopicQos::kStream));
  ASSERT_NE(writer, nullptr);
  const auto t0 = now_ns();
  while (!both_matched(reader, writer) && seconds_between(t0, now_ns()) < 20.0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_TRUE(both_matched(reader, writer));
  MasterCommandPubSubType type;
  MasterCommand c;
  c.enabled(true);
  eprosima::fastrtps::rtps::SerializedPayload_t payload(type.m_typeSize);
  ASSERT_TRUE(type.serialize(&c, &payload));
  Blob bad{std::vector<std::uint8_t>(payload.data, payload.data + payload.length)};
  bad.bytes[1] = 9;  // an encapsulation kind that does not exist: deserialize() fails
  for (int i = 0; i < 10; ++i) {
    writer->write(&bad);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  const auto t1 = now_ns();
  while (reader.malformed() < 10 && seconds_between(t1, now_ns()) < 3.0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_GE(reader.malformed(), 5u);
  EXPECT_LE(reader.malformed(), 10u);
  EXPECT_EQ(received.load(), 0);
  hostile.publisher()->delete_datawriter(writer);
}

}  // namespace
}  // namespace teleop::dds
