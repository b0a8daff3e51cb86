#include "client/record/topic_table.hpp"

#include <memory>
#include <stdexcept>

#include "teleop/idl/DevicePubSubTypes.h"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::record {

namespace {
template <class T>
eprosima::fastdds::dds::TopicDataType* make() {
  return new T();
}
}  // namespace

const std::vector<TopicEntry>& known_topics() {
  using dds::TopicQos;
  namespace t = dds::topics;
  static const std::vector<TopicEntry> table = {
      {t::kMasterCommand, "", TopicQos::kStream, &make<MasterCommandPubSubType>},
      {t::kSlaveState, "", TopicQos::kStream, &make<SlaveStatePubSubType>},
      {t::kMasterState, "", TopicQos::kStream, &make<MasterStatePubSubType>},
      {t::kScene, "", TopicQos::kLatched, &make<SceneDescriptionPubSubType>},
      {t::kMeshTopology, "", TopicQos::kLatched, &make<MeshTopologyPubSubType>},
      {t::kMeshFrame, "", TopicQos::kStream, &make<MeshFramePubSubType>},
      {t::kEvents, "", TopicQos::kEventLog, &make<EventPubSubType>},
      {t::kServerStats, "", TopicQos::kReliableStream, &make<ServerStatsPubSubType>},
      // the master's answers to live tuning (what was applied, when); the requests themselves
      // are not recorded, so that playing a recording can never retune a running master
      {t::kTuningStatus, "", TopicQos::kLatched, &make<TuningStatusPubSubType>},
      // what the session is (scheme, gains, injected delays, loop delay, device)
      {t::kExperiment, "", TopicQos::kLatched, &make<ExperimentDescriptionPubSubType>},
      // the observers' rate-limited copies: recorded too, so that a played session reaches
      // monitors and viewers on their default (rate-limited) topics
      {t::kSlaveStateView, "", TopicQos::kLatest, &make<SlaveStatePubSubType>},
      {t::kSlaveStateMonitor, "", TopicQos::kLatest, &make<SlaveStatePubSubType>},
      {t::kMasterStateView, "", TopicQos::kLatest, &make<MasterStatePubSubType>},
      {t::kMasterStateMonitor, "", TopicQos::kLatest, &make<MasterStatePubSubType>},
      {t::kMeshFrameMonitor, "", TopicQos::kLatest, &make<MeshFramePubSubType>},
      {"teleop/device_state", "", TopicQos::kStream, &make<DeviceStatePubSubType>},
      {"teleop/device_command", "", TopicQos::kStream, &make<DeviceCommandPubSubType>},
  };
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
