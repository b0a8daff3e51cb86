#pragma once
// DDS participant factory and typed writer/reader helpers (Fast DDS 2.9).
//
// Profiles are XML files in deploy/profiles/<name>.xml holding a participant profile of the
// same name. The default, `loopback`, sends nothing beyond 127.0.0.1. Choose another with
// --profile (or TELEOP_PROFILE), the domain with --domain (or TELEOP_DOMAIN), and the folder
// with TELEOP_PROFILES_DIR. Every return code is checked; failures throw DdsError with a
// message that says what failed.
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

namespace teleop::dds {

class DdsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Which participant to create.
struct ParticipantOptions {
  std::string profile = "loopback";  ///< profile name == file stem in the profiles folder
  int domain = 0;                    ///< DDS domain id [0, 232]
  std::string name = "teleop";       ///< participant name shown in tools
};

/// Resolves options: explicit flag > environment (TELEOP_PROFILE, TELEOP_DOMAIN) > default.
/// @throws config::ConfigError for an out-of-range domain or malformed environment value.
ParticipantOptions resolve_participant_options(const std::optional<std::string>& profile_flag,
                                               const std::optional<int>& domain_flag,
                                               const std::string& name);

/// Path of the XML file for a profile name, or the name itself if it is a path to a file.
/// @throws config::ConfigError if the file does not exist (lists the available profiles).
std::string profile_file(const std::string& profile);

/// Quality of service of each topic of the design's topic table.
enum class TopicQos {
  kStream,          ///< best effort, keep last 1, volatile: hot state and commands
  kLatched,         ///< reliable, transient local, keep last 1: scene, mesh topology
  kEventLog,        ///< reliable, transient local, keep last 100: events
  kReliableStream,  ///< reliable, volatile, keep last 10: stats
};

/// A participant with one publisher and one subscriber. Deletes all contained entities on
/// destruction.
class Participant {
 public:
  explicit Participant(const ParticipantOptions& options);
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  /// Registers `type` (once per name) and returns the topic (created once per name).
  eprosima::fastdds::dds::Topic* topic(const std::string& topic_name,
                                       eprosima::fastdds::dds::TypeSupport type);

  eprosima::fastdds::dds::DomainParticipant* raw() { return participant_; }
  eprosima::fastdds::dds::Publisher* publisher() { return publisher_; }
  eprosima::fastdds::dds::Subscriber* subscriber() { return subscriber_; }
  const ParticipantOptions& options() const { return options_; }

 private:
  ParticipantOptions options_;
  eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
  eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
  eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
  std::map<std::string, eprosima::fastdds::dds::Topic*> topics_;
};

/// DataWriter QoS for a TopicQos class (XCDR1 data representation, for other vendors).
eprosima::fastdds::dds::DataWriterQos writer_qos(eprosima::fastdds::dds::Publisher* pub,
                                                 TopicQos qos);
/// DataReader QoS for a TopicQos class.
eprosima::fastdds::dds::DataReaderQos reader_qos(eprosima::fastdds::dds::Subscriber* sub,
                                                 TopicQos qos);

/// Topic names of the design's topic table.
namespace topics {
inline constexpr const char* kMasterCommand = "teleop/master_command";
inline constexpr const char* kSlaveState = "teleop/slave_state";
inline constexpr const char* kMasterState = "teleop/master_state";
inline constexpr const char* kScene = "teleop/scene";
inline constexpr const char* kMeshTopology = "teleop/mesh_topology";
inline constexpr const char* kMeshFrame = "teleop/mesh_frame";
inline constexpr const char* kEvents = "teleop/events";
inline constexpr const char* kServerStats = "teleop/server_stats";
}  // namespace topics

}  // namespace teleop::dds
