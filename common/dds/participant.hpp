#pragma once
// DDS participant factory and typed writer/reader helpers (Fast DDS 2.9).
//
// Profiles are participant profiles in the XML files of deploy/profiles/ (a file may hold
// several, e.g. wan_tcp.xml holds wan_tcp_server and wan_tcp_client): a profile NAME is found
// by its profile_name, whatever the file is called. The default, `loopback`, sends nothing
// beyond 127.0.0.1. Choose another with --profile (or TELEOP_PROFILE), the domain with --domain
// (or TELEOP_DOMAIN), and the folder with TELEOP_PROFILES_DIR. Addresses and ports of the
// multi-machine profiles come from flags or environment (NetworkOptions), never from editing
// the XML: they are put into the participant QoS in code. Every return code is checked;
// failures throw DdsError with a message that says what failed.
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
#include <vector>

namespace teleop::dds {

class DdsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// An IPv4 address and a port (0: the profile's default).
struct HostPort {
  std::string address;
  int port = 0;
  bool operator==(const HostPort&) const = default;
};

/// DDS Security of the secure profiles (docs/networking.md, "Security"): where the files are.
/// The layout is deploy/make_security.sh's: DIR/identity_ca.cert.pem,
/// DIR/permissions_ca.cert.pem, DIR/governance.p7s and DIR/IDENTITY/{identity.cert.pem,
/// identity.key.pem, permissions.p7s}.
struct SecurityOptions {
  std::string dir;              ///< --security-dir / TELEOP_SECURITY_DIR (empty: none given)
  std::string dir_source;       ///< "--security-dir" or "TELEOP_SECURITY_DIR" (for messages)
  std::string identity;         ///< --identity / TELEOP_IDENTITY, else the executable's role
  std::string identity_source;  ///< "--identity", "TELEOP_IDENTITY" or "" (the default)
  bool operator==(const SecurityOptions&) const = default;
};

/// The files DDS Security reads for one identity, checked to exist and to look right.
struct SecurityFiles {
  std::string identity_ca;           ///< DIR/identity_ca.cert.pem
  std::string identity_certificate;  ///< DIR/IDENTITY/identity.cert.pem
  std::string private_key;           ///< DIR/IDENTITY/identity.key.pem
  std::string permissions_ca;        ///< DIR/permissions_ca.cert.pem
  std::string governance;            ///< DIR/governance.p7s
  std::string permissions;           ///< DIR/IDENTITY/permissions.p7s
};

/// The files of `security` after checking that each exists, is readable and holds what it
/// should (a PEM certificate, a PEM private key, an S/MIME-signed document).
/// @throws config::ConfigError naming the flag (or variable), the path and what is missing.
SecurityFiles security_files(const SecurityOptions& security);

/// Addresses and ports of the multi-machine profiles (docs/networking.md).
struct NetworkOptions {
  std::vector<HostPort> peers;              ///< --peer / TELEOP_PEERS: unicast initial peers
  int listen_port = 0;                      ///< --listen / TELEOP_LISTEN_PORT: TCP port (0: 5100)
  std::string public_address;               ///< --public-address / TELEOP_PUBLIC_ADDRESS (TCP WAN)
  std::vector<HostPort> discovery_servers;  ///< --discovery-server / TELEOP_DISCOVERY_SERVERS
  SecurityOptions security = {};            ///< secure profiles: --security-dir, --identity
};

/// The network flags as typed on the command line (unparsed); see network_flags.hpp.
struct NetworkFlags {
  std::vector<std::string> peers;
  std::optional<std::string> listen;
  std::optional<std::string> public_address;
  std::vector<std::string> discovery_servers;
  std::optional<std::string> security_dir;    ///< --security-dir DIR
  std::optional<std::string> identity;        ///< --identity NAME
  bool insecure = false;                      ///< --insecure (or TELEOP_INSECURE=1)
  std::string default_identity = "observer";  ///< the executable's role when --identity is absent
};

/// Which participant to create.
struct ParticipantOptions {
  std::string profile = "loopback";  ///< participant profile name (or an XML file path)
  int domain = 0;                    ///< DDS domain id [0, 232]
  std::string name = "teleop";       ///< participant name shown in tools
  NetworkOptions network = {};       ///< addresses for the multi-machine profiles
  /// UDP profiles: announce this participant to every participant id of the domain on each
  /// initial peer (kWholeDomainPeers), not only to the profile's maxInitialPeersRange. The server
  /// and the master set it, so that observers with any participant id find them; observers
  /// keep the profile's range and reach the server through its announcements.
  bool announce_to_whole_domain = false;
  /// The profile reaches beyond 127.0.0.1 without DDS Security, accepted with --insecure:
  /// programs say so at start and in their status.
  bool insecure = false;
};

/// Participant ids of one domain on one host whose ports stay within the domain's block:
/// metatraffic unicast port 7400 + 250 domain + 10 + 2 id, user unicast + 1, below the next
/// domain's 7400 + 250 (domain + 1).
inline constexpr int kWholeDomainPeers = 120;

/// Resolves options: explicit flag > environment (TELEOP_PROFILE, TELEOP_DOMAIN, TELEOP_PEERS,
/// TELEOP_LISTEN_PORT, TELEOP_PUBLIC_ADDRESS, TELEOP_DISCOVERY_SERVERS, TELEOP_SECURITY_DIR,
/// TELEOP_IDENTITY) > default, and checks that the profile exists and that the network and
/// security options fit it (a secure profile's files exist and look right).
/// @throws config::ConfigError naming the flag (or variable) and the value.
ParticipantOptions resolve_participant_options(const std::optional<std::string>& profile_flag,
                                               const std::optional<int>& domain_flag,
                                               const std::string& name,
                                               const NetworkFlags& net = {});

/// Parses "a.b.c.d[:port]" given by `flag` (port 1-65535; none: default_port).
/// @throws config::ConfigError naming the flag and the value.
HostPort parse_host_port(const std::string& flag, const std::string& text, int default_port);

/// Where a participant profile is defined.
struct ProfileRef {
  std::string file;  ///< XML file
  std::string name;  ///< participant profile_name in it
};

/// Every participant profile of the profiles folder: name -> file.
std::map<std::string, std::string> profile_index();

/// The file and name of a profile given as a NAME (looked up in every XML file of the profiles
/// folder) or as a path to an XML file (its participant profile named like the file, else its
/// only one). @throws config::ConfigError listing the available profiles.
ProfileRef resolve_profile(const std::string& profile);

/// Path of the XML file defining a profile (resolve_profile(profile).file).
std::string profile_file(const std::string& profile);

/// How a profile uses the network options.
enum class ProfileKind {
  kUdp,              ///< UDP (loopback, lan, lan_unicast): --peer adds unicast peers
  kTcp,              ///< TCPv4 (wan_tcp_*): --listen, --public-address, --peer ADDR[:5100]
  kDiscoveryClient,  ///< discovery client: --discovery-server ADDR[:11811], one per server id
};

/// True when a participant QoS can send beyond this host: a TCP transport, a UDP transport not
/// restricted to 127.0.0.1, or Fast DDS's built-in transports.
bool reaches_beyond_loopback(const eprosima::fastdds::dds::DomainParticipantQos& qos);

/// True when a participant QoS turns DDS Security on (the profile sets dds.sec.auth.plugin).
bool is_secure(const eprosima::fastdds::dds::DomainParticipantQos& qos);

/// The participant QoS of the options: the XML profile with the network options applied; for
/// a secure profile, the security files' paths added as the plugins' properties.
/// @throws config::ConfigError when an option does not fit the profile (names the flag).
eprosima::fastdds::dds::DomainParticipantQos participant_qos(const ParticipantOptions& options,
                                                             ProfileKind* kind = nullptr);

/// Quality-of-service classes of the topics (the topic table: common/dds/topics.hpp).
enum class TopicQos {
  kStream,          ///< best effort, keep last 1, volatile: hot state and commands
  kLatched,         ///< reliable, transient local, keep last 1: scene, mesh topology
  kEventLog,        ///< reliable, transient local, keep last 100: events
  kReliableStream,  ///< reliable, volatile, keep last 10: stats
  kLatest,          ///< best effort, volatile, keep last 1: the rate-limited observer copies
                    ///< (a late observer gets the next copy, within one period)
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

}  // namespace teleop::dds
