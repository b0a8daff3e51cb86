// The raw type support and the topic table of the recorder and the player: payloads pass
// byte for byte, keys match the generated type, every design topic is known with its QoS.
#include <gtest/gtest.h>

#include "client/record/raw_type.hpp"
#include "client/record/topic_table.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::record {
namespace {

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
  EXPECT_EQ(known_topics().size(), 17u);
  // the master's tuning answers are recorded; the requests are not (playing a recording must
  // never retune a running master)
  ASSERT_NE(find_topic("teleop/tuning_status"), nullptr);
  EXPECT_EQ(find_topic("teleop/tuning_status")->qos, dds::TopicQos::kLatched);
  EXPECT_EQ(find_topic("teleop/tuning"), nullptr);
  ASSERT_NE(find_topic("teleop/events"), nullptr);
  // the session's description is latched, so a played recording describes itself at once
  ASSERT_NE(find_topic("teleop/experiment"), nullptr);
  EXPECT_EQ(find_topic("teleop/experiment")->qos, dds::TopicQos::kLatched);
  EXPECT_EQ(find_topic("teleop/experiment")->type, "teleop::ExperimentDescription");
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
