// The recording file (SQLite + zstd) and the raw type support: what goes in comes out, byte
// for byte, in receive order, from a seek point; a file that is not a recording is refused.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>

#include "client/record/raw_type.hpp"
#include "client/record/recording.hpp"
#include "client/record/topic_table.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::record {
namespace {

std::string tmp(const std::string& name) {
  return "/tmp/teleop_recording_test_" + std::to_string(getpid()) + "_" + name;
}

TEST(Recording, RoundTripInReceiveOrderWithSeek) {
  const std::string path = tmp("a.db");
  std::vector<RecordedSample> in;
  {
    RecordingWriter w(path);
    const int a = w.add_topic("teleop/slave_state", "teleop::SlaveState", "stream");
    const int b = w.add_topic("teleop/mesh_frame", "teleop::MeshFrame", "stream");
    for (int i = 0; i < 100; ++i) {
      RecordedSample s;
      s.topic_id = i % 3 == 0 ? b : a;
      s.receive_ns = 1'000'000'000LL + i * 1'000'000LL;
      s.source_ns = s.receive_ns - 50'000;
      s.writer_seq = i + 1;
      s.writer_guid[15] = static_cast<std::uint8_t>(s.topic_id);
      // large, compressible payloads for one topic (zstd path), small ones for the other
      s.payload.resize(s.topic_id == b ? 30000 : 200);
      for (std::size_t k = 0; k < s.payload.size(); ++k) {
        s.payload[k] = static_cast<std::uint8_t>(s.topic_id == b ? (k / 64) : (k * 31 + i));
      }
      in.push_back(s);
    }
    w.append(in);
    w.set_meta("domain", "7");
    EXPECT_LT(w.stored_bytes(), w.raw_bytes());  // the large payloads were compressed
  }
  RecordingReader r(path);
  ASSERT_EQ(r.topics().size(), 2u);
  EXPECT_EQ(r.topics()[0].name, "teleop/slave_state");
  EXPECT_EQ(r.meta().at("domain"), "7");
  EXPECT_EQ(r.first_ns(), in.front().receive_ns);
  EXPECT_EQ(r.last_ns(), in.back().receive_ns);
  r.scan(in[40].receive_ns);
  RecordedSample s;
  std::size_t i = 40;
  while (r.next(s)) {
    ASSERT_LT(i, in.size());
    EXPECT_EQ(s.receive_ns, in[i].receive_ns);
    EXPECT_EQ(s.source_ns, in[i].source_ns);
    EXPECT_EQ(s.writer_seq, in[i].writer_seq);
    EXPECT_EQ(s.writer_guid[15], in[i].writer_guid[15]);
    EXPECT_EQ(s.payload, in[i].payload);
    ++i;
  }
  EXPECT_EQ(i, in.size());
  // one topic, a time window
  r.scan(in[0].receive_ns, in[10].receive_ns, {r.topics()[1].id});
  int n = 0;
  while (r.next(s)) ++n;
  EXPECT_EQ(n, 4);  // samples 0, 3, 6, 9
  std::remove(path.c_str());
}

TEST(Recording, NotARecordingIsRefused) {
  const std::string path = tmp("b.db");
  { std::ofstream(path) << "hello"; }
  EXPECT_THROW(RecordingReader r(path), RecordingError);
  EXPECT_THROW(RecordingReader r(tmp("missing.db")), RecordingError);
  std::remove(path.c_str());
}

TEST(RawType, PayloadsAreTheGeneratedSerialisationByteForByte) {
  SlaveStatePubSubType typed;
  SlaveState st;
  st.seq(42);
  st.tip_position_m({0.1, 0.2, 0.3});
  st.in_contact(true);
  eprosima::fastrtps::rtps::SerializedPayload_t p(typed.getSerializedSizeProvider(&st)());
  ASSERT_TRUE(typed.serialize(&st, &p));
  RawPubSubType raw(new SlaveStatePubSubType());
  EXPECT_EQ(std::string(raw.getName()), std::string(typed.getName()));
  RawSample rs;
  ASSERT_TRUE(raw.deserialize(&p, &rs));
  EXPECT_EQ(rs.bytes.size(), p.length);
  // and back: the raw writer's payload decodes with the generated type
  eprosima::fastrtps::rtps::SerializedPayload_t q(raw.getSerializedSizeProvider(&rs)());
  ASSERT_TRUE(raw.serialize(&rs, &q));
  SlaveState back;
  ASSERT_TRUE(typed.deserialize(&q, &back));
  EXPECT_EQ(back.seq(), 42u);
  EXPECT_EQ(back.tip_position_m()[2], 0.3);
  EXPECT_TRUE(back.in_contact());
}

TEST(RawType, KeyOfAKeyedTopicMatchesTheGeneratedOne) {
  MeshFramePubSubType typed;
  MeshFrame f;
  f.object_id(17);
  eprosima::fastrtps::rtps::SerializedPayload_t p(typed.getSerializedSizeProvider(&f)());
  ASSERT_TRUE(typed.serialize(&f, &p));
  RawPubSubType raw(new MeshFramePubSubType());
  ASSERT_TRUE(raw.m_isGetKeyDefined);
  RawSample rs;
  ASSERT_TRUE(raw.deserialize(&p, &rs));
  eprosima::fastrtps::rtps::InstanceHandle_t h1, h2;
  ASSERT_TRUE(typed.getKey(&f, &h1));
  ASSERT_TRUE(raw.getKey(&rs, &h2));
  EXPECT_EQ(h1, h2);
}

TEST(TopicTable, EveryDesignTopicWithItsQos) {
  EXPECT_EQ(known_topics().size(), 16u);
  // the master's tuning answers are recorded; the requests are not (playing a recording must
  // never retune a running master)
  ASSERT_NE(find_topic("teleop/tuning_status"), nullptr);
  EXPECT_EQ(find_topic("teleop/tuning_status")->qos, dds::TopicQos::kLatched);
  EXPECT_EQ(find_topic("teleop/tuning"), nullptr);
  ASSERT_NE(find_topic("teleop/events"), nullptr);
  // the observers' rate-limited copies are recorded (and played) with their own QoS class
  ASSERT_NE(find_topic("teleop/slave_state_monitor"), nullptr);
  EXPECT_EQ(find_topic("teleop/slave_state_monitor")->qos, dds::TopicQos::kLatest);
  EXPECT_EQ(find_topic("teleop/slave_state_view")->type, "teleop::SlaveState");
  EXPECT_EQ(find_topic("teleop/mesh_frame_monitor")->type, "teleop::MeshFrame");
  EXPECT_FALSE(is_latched(dds::TopicQos::kLatest));  // --seek does not replay them first
  EXPECT_EQ(find_topic("teleop/events")->qos, dds::TopicQos::kEventLog);
  EXPECT_EQ(find_topic("teleop/scene")->type, "teleop::SceneDescription");
  for (const auto& e : known_topics()) {
    EXPECT_EQ(qos_from_name(qos_name(e.qos)), e.qos);
  }
  EXPECT_THROW(qos_from_name("nope"), std::invalid_argument);
}

}  // namespace
}  // namespace teleop::record
