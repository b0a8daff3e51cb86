#pragma once
// The topics a recorder records and a player plays: every topic of the topic table
// (common/dds/topics.hpp) but the tuning requests, each with the QoS class its live writers use.
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <string>
#include <vector>

#include "common/dds/topics.hpp"

namespace teleop::record {

struct TopicEntry {
  std::string name;   ///< DDS topic name, e.g. "teleop/slave_state"
  std::string type;   ///< DDS type name, e.g. "teleop::SlaveState"
  dds::TopicQos qos;  ///< QoS class of the live writers
  /// New generated type support of the topic (caller owns it).
  eprosima::fastdds::dds::TopicDataType* (*make_type)();
};

/// Every known topic, in the order of the design's table.
const std::vector<TopicEntry>& known_topics();
/// The entry of a topic name, or nullptr.
const TopicEntry* find_topic(const std::string& name);

/// "stream", "latched", "event_log", "reliable_stream".
std::string qos_name(dds::TopicQos qos);
/// Inverse of qos_name. @throws std::invalid_argument for another text.
dds::TopicQos qos_from_name(const std::string& name);
/// True for the QoS classes whose writers keep history for late joiners (transient local).
bool is_latched(dds::TopicQos qos);

}  // namespace teleop::record
