#include "client/record/topic_table.hpp"

#include <memory>
#include <stdexcept>

namespace teleop::record {

namespace {
template <class T>
eprosima::fastdds::dds::TopicDataType* make() {
  return new T();
}
}  // namespace

const std::vector<TopicEntry>& known_topics() {
  // every topic of the table (common/dds/topics.hpp), with the QoS class its live writers use.
  // The observers' rate-limited copies are recorded too, so that a played session reaches
  // monitors and viewers on their default topics. The master's answers to live tuning are
  // recorded, the requests themselves (teleop/tuning) are not, so that playing a recording can
  // never retune a running master.
  static const std::vector<TopicEntry> table = [] {
    std::vector<TopicEntry> out;
    dds::topics::for_each([&out](const auto& t) {
      if (std::string(t.name) == dds::topics::kTuning.name) return;
      out.push_back({t.name, "", t.qos, &make<dds::PubSubOf<decltype(t)>>});
    });
    return out;
  }();
  static const std::vector<TopicEntry> named = [] {
    std::vector<TopicEntry> out = table;
    for (auto& e : out) {
      std::unique_ptr<eprosima::fastdds::dds::TopicDataType> ty(e.make_type());
      e.type = ty->getName();
    }
    return out;
  }();
  return named;
}

const TopicEntry* find_topic(const std::string& name) {
  for (const auto& e : known_topics()) {
    if (e.name == name) return &e;
  }
  return nullptr;
}

std::string qos_name(dds::TopicQos qos) {
  switch (qos) {
    case dds::TopicQos::kStream:
      return "stream";
    case dds::TopicQos::kLatched:
      return "latched";
    case dds::TopicQos::kEventLog:
      return "event_log";
    case dds::TopicQos::kReliableStream:
      return "reliable_stream";
    case dds::TopicQos::kLatest:
      return "latest";
  }
  return "stream";
}

dds::TopicQos qos_from_name(const std::string& name) {
  if (name == "stream") return dds::TopicQos::kStream;
  if (name == "latched") return dds::TopicQos::kLatched;
  if (name == "event_log") return dds::TopicQos::kEventLog;
  if (name == "reliable_stream") return dds::TopicQos::kReliableStream;
  if (name == "latest") return dds::TopicQos::kLatest;
  throw std::invalid_argument("unknown QoS class '" + name + "'");
}

bool is_latched(dds::TopicQos qos) {
  return qos == dds::TopicQos::kLatched || qos == dds::TopicQos::kEventLog;
}

}  // namespace teleop::record
