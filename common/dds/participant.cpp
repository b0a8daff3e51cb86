#include "common/dds/participant.hpp"

#include <fastdds/dds/core/policy/QosPolicies.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <filesystem>
#include <mutex>
#include <set>

#include "common/config/config.hpp"

#ifndef TELEOP_DEFAULT_PROFILES_DIR
#define TELEOP_DEFAULT_PROFILES_DIR "deploy/profiles"
#endif

namespace teleop::dds {

using namespace eprosima::fastdds::dds;
namespace fs = std::filesystem;

namespace {
std::string profiles_dir() {
  if (const char* env = std::getenv("TELEOP_PROFILES_DIR"); env && *env) return env;
  return TELEOP_DEFAULT_PROFILES_DIR;
}
}  // namespace

std::string profile_file(const std::string& profile) {
  if (profile.find('/') != std::string::npos || profile.ends_with(".xml")) {
    if (!fs::exists(profile)) {
      throw config::ConfigError("--profile '" + profile + "': file does not exist");
    }
    return profile;
  }
  const fs::path p = fs::path(profiles_dir()) / (profile + ".xml");
  if (!fs::exists(p)) {
    std::string names;
    if (fs::is_directory(profiles_dir())) {
      std::set<std::string> sorted;
      for (const auto& e : fs::directory_iterator(profiles_dir())) {
        if (e.path().extension() == ".xml") sorted.insert(e.path().stem().string());
      }
      for (const auto& s : sorted) names += (names.empty() ? "" : ", ") + s;
    }
    throw config::ConfigError("--profile '" + profile + "': no file " + p.string() +
                              "; available profiles: {" + names + "}");
  }
  return p.string();
}

ParticipantOptions resolve_participant_options(const std::optional<std::string>& profile_flag,
                                               const std::optional<int>& domain_flag,
                                               const std::string& name) {
  ParticipantOptions o;
  o.name = name;
  if (profile_flag) {
    o.profile = *profile_flag;
  } else if (const char* env = std::getenv("TELEOP_PROFILE"); env && *env) {
    o.profile = env;
  }
  if (domain_flag) {
    o.domain = *domain_flag;
  } else if (const char* env = std::getenv("TELEOP_DOMAIN"); env && *env) {
    try {
      std::size_t pos = 0;
      o.domain = std::stoi(env, &pos);
      if (pos != std::string(env).size()) throw std::invalid_argument("trailing");
    } catch (const std::exception&) {
      throw config::ConfigError(std::string("environment: TELEOP_DOMAIN='") + env +
                                "' is not an integer in [0, 232]");
    }
  }
  if (o.domain < 0 || o.domain > 232) {
    throw config::ConfigError("--domain " + std::to_string(o.domain) +
                              " is out of the allowed range [0, 232]");
  }
  return o;
}

Participant::Participant(const ParticipantOptions& options) : options_(options) {
  auto* factory = DomainParticipantFactory::get_instance();
  const std::string file = profile_file(options.profile);
  // loading the same file twice is harmless, but guard concurrent loads in one process
  static std::mutex load_mutex;
  static std::set<std::string> loaded;
  {
    std::lock_guard<std::mutex> lock(load_mutex);
    if (!loaded.count(file)) {
      if (factory->load_XML_profiles_file(file) != ReturnCode_t::RETCODE_OK) {
        throw DdsError("cannot load Fast DDS XML profiles from " + file);
      }
      loaded.insert(file);
    }
  }
  const std::string profile_name = fs::path(options.profile).stem().string();
  participant_ = factory->create_participant_with_profile(static_cast<DomainId_t>(options.domain),
                                                          profile_name);
  if (!participant_) {
    throw DdsError("cannot create a DDS participant with profile '" + profile_name + "' from " +
                   file + " on domain " + std::to_string(options.domain));
  }
  publisher_ = participant_->create_publisher(PUBLISHER_QOS_DEFAULT);
  subscriber_ = participant_->create_subscriber(SUBSCRIBER_QOS_DEFAULT);
  if (!publisher_ || !subscriber_) {
    participant_->delete_contained_entities();
    factory->delete_participant(participant_);
    throw DdsError("cannot create the DDS publisher/subscriber");
  }
}

Participant::~Participant() {
  if (participant_) {
    participant_->delete_contained_entities();
    DomainParticipantFactory::get_instance()->delete_participant(participant_);
  }
}

Topic* Participant::topic(const std::string& topic_name, TypeSupport type) {
  auto it = topics_.find(topic_name);
  if (it != topics_.end()) return it->second;
  const std::string type_name = type.get_type_name();
  if (participant_->find_type(type_name).empty()) {
    if (type.register_type(participant_) != ReturnCode_t::RETCODE_OK) {
      throw DdsError("cannot register DDS type " + type_name);
    }
  }
  Topic* t = participant_->create_topic(topic_name, type_name, TOPIC_QOS_DEFAULT);
  if (!t) throw DdsError("cannot create DDS topic " + topic_name + " of type " + type_name);
  topics_[topic_name] = t;
  return t;
}

namespace {
template <class Qos>
void apply(Qos& q, TopicQos qos) {
  switch (qos) {
    case TopicQos::kStream:
      q.reliability().kind = BEST_EFFORT_RELIABILITY_QOS;
      q.durability().kind = VOLATILE_DURABILITY_QOS;
      q.history().kind = KEEP_LAST_HISTORY_QOS;
      q.history().depth = 1;
      break;
    case TopicQos::kLatched:
      q.reliability().kind = RELIABLE_RELIABILITY_QOS;
      q.durability().kind = TRANSIENT_LOCAL_DURABILITY_QOS;
      q.history().kind = KEEP_LAST_HISTORY_QOS;
      q.history().depth = 1;
      break;
    case TopicQos::kEventLog:
      q.reliability().kind = RELIABLE_RELIABILITY_QOS;
      q.durability().kind = TRANSIENT_LOCAL_DURABILITY_QOS;
      q.history().kind = KEEP_LAST_HISTORY_QOS;
      q.history().depth = 100;
      break;
    case TopicQos::kReliableStream:
      q.reliability().kind = RELIABLE_RELIABILITY_QOS;
      q.durability().kind = VOLATILE_DURABILITY_QOS;
      q.history().kind = KEEP_LAST_HISTORY_QOS;
      q.history().depth = 10;
      break;
  }
}
}  // namespace

DataWriterQos writer_qos(Publisher* pub, TopicQos qos) {
  DataWriterQos q = pub->get_default_datawriter_qos();
  apply(q, qos);
  if (qos == TopicQos::kStream) {
    // same-host readers may read straight from the writer's history (Fast DDS data sharing
    // for bounded types): with depth 1 a burst of writes overwrites samples before they are
    // taken. A best-effort volatile writer sends each sample at once, so depth costs nothing.
    q.history().depth = 16;
  }
  if (qos != TopicQos::kStream) {
    // short heartbeat: small reliable samples in bursts recover quickly (REFERENCE.md)
    q.reliable_writer_qos().times.heartbeatPeriod.seconds = 0;
    q.reliable_writer_qos().times.heartbeatPeriod.nanosec = 100'000'000;
  }
  // no data sharing: it maps the writer's history into other processes (boost interprocess),
  // the same machinery that aborts a survivor when a peer dies holding its mutex
  q.data_sharing().off();
  q.representation().m_value.clear();
  q.representation().m_value.push_back(XCDR_DATA_REPRESENTATION);
  return q;
}

DataReaderQos reader_qos(Subscriber* sub, TopicQos qos) {
  DataReaderQos q = sub->get_default_datareader_qos();
  apply(q, qos);
  q.data_sharing().off();
  if (qos == TopicQos::kStream) {
    // the writer keeps only the newest sample; the reader holds a few so that a burst arriving
    // between two takes (e.g. from a jittered channel) is counted, not silently overwritten
    q.history().depth = 16;
  }
  return q;
}

}  // namespace teleop::dds
