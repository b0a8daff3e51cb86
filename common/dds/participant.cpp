#include "common/dds/participant.hpp"

#include <arpa/inet.h>
#include <unistd.h>
#include <fastdds/dds/core/policy/QosPolicies.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>

#include <fastdds/rtps/attributes/PropertyPolicy.h>
#include <fastdds/rtps/attributes/ServerAttributes.h>
#include <fastdds/rtps/transport/TCPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/shared_mem/SharedMemTransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <regex>
#include <set>
#include <sstream>

#include "common/config/config.hpp"
#include "common/dds/log_summary.hpp"
#include "common/dds/security_check.hpp"
#include "common/util/data_dir.hpp"

namespace teleop::dds {

using namespace eprosima::fastdds::dds;
namespace fs = std::filesystem;

namespace {
std::string profiles_dir() {
  if (const char* env = std::getenv("TELEOP_PROFILES_DIR"); env && *env) return env;
  return data_path("profiles");
}

std::string slurp(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

/// participant profile names defined in an XML text, in order
std::vector<std::string> participant_profiles(const std::string& xml) {
  static const std::regex re(R"re(<participant\s[^>]*profile_name\s*=\s*"([^"]+)")re");
  std::vector<std::string> names;
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), re); it != std::sregex_iterator();
       ++it) {
    names.push_back((*it)[1].str());
  }
  return names;
}

std::string join(const std::vector<std::string>& v) {
  std::string out;
  for (const auto& s : v) out += (out.empty() ? "" : ", ") + s;
  return out;
}

std::vector<std::string> available_profiles() {
  std::vector<std::string> names;
  for (const auto& [name, file] : profile_index()) names.push_back(name);
  return names;
}

int parse_port(const std::string& flag, const std::string& whole, const std::string& text) {
  bool digits = !text.empty() && text.size() <= 5;
  for (char c : text) digits = digits && std::isdigit(static_cast<unsigned char>(c));
  const long port = digits ? std::stol(text) : -1;
  if (port < 1 || port > 65535) {
    throw config::ConfigError(flag + " '" + whole + "': '" + text +
                              "' is not a port number in [1, 65535]");
  }
  return static_cast<int>(port);
}

void check_ipv4(const std::string& flag, const std::string& whole, const std::string& address,
                const std::string& expected) {
  in_addr a{};
  if (address.empty() || inet_pton(AF_INET, address.c_str(), &a) != 1) {
    throw config::ConfigError(flag + " '" + whole + "': '" + address +
                              "' is not an IPv4 address (expected " + expected + ")");
  }
}

/// "a,b;c" -> {a, b, c} (environment lists)
std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : text) {
    if (c == ',' || c == ';' || c == ' ') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

const char* env_or_null(const char* name) {
  const char* v = std::getenv(name);
  return (v && *v) ? v : nullptr;
}

/// The secure profiles of the profiles folder (names starting with "secure"), for messages.
std::string secure_profile_names() {
  std::vector<std::string> names;
  for (const auto& [name, file] : profile_index()) {
    if (name.starts_with("secure")) names.push_back(name);
  }
  return names.empty() ? std::string("none in ") + profiles_dir() : join(names);
}

/// "--security-dir 'DIR'" or "TELEOP_SECURITY_DIR='DIR'"
std::string security_dir_label(const SecurityOptions& s) {
  return s.dir_source == "TELEOP_SECURITY_DIR" ? "TELEOP_SECURITY_DIR='" + s.dir + "'"
                                               : "--security-dir '" + s.dir + "'";
}

/// Checks one security file: exists, is a readable regular file holding `marker`.
void check_security_file(const SecurityOptions& s, const std::string& path, const std::string& what,
                         const std::string& marker, const std::string& expected) {
  const std::string where = security_dir_label(s) + " (identity '" + s.identity + "'" +
                            (s.identity_source.empty() ? ", the default of this program"
                                                       : ", from " + s.identity_source) +
                            "): ";
  const std::string hint = " (make the files with deploy/make_security.sh; docs/networking.md)";
  std::error_code ec;
  if (!fs::exists(path, ec)) {
    throw config::ConfigError(where + "missing " + path + ": " + what + hint);
  }
  if (!fs::is_regular_file(path, ec)) {
    throw config::ConfigError(where + path + " is not a regular file: " + what + hint);
  }
  std::ifstream f(path);
  if (!f) throw config::ConfigError(where + "cannot read " + path + " (permissions?): " + what);
  std::stringstream ss;
  ss << f.rdbuf();
  const std::string text = ss.str();
  if (text.empty()) throw config::ConfigError(where + path + " is empty: " + what + hint);
  if (text.find(marker) == std::string::npos) {
    throw config::ConfigError(where + path + " does not hold " + what + " (expected " + expected +
                              ")" + hint);
  }
}

std::string file_uri(const std::string& path) { return "file://" + path; }

constexpr int kDefaultTcpPort = 5100;
constexpr int kDefaultDiscoveryPort = 11811;

void load_once(const std::string& file) {
  // loading the same file twice is harmless, but guard concurrent loads in one process
  static std::mutex load_mutex;
  static std::set<std::string> loaded;
  std::lock_guard<std::mutex> lock(load_mutex);
  if (loaded.count(file)) return;
  if (DomainParticipantFactory::get_instance()->load_XML_profiles_file(file) !=
      ReturnCode_t::RETCODE_OK) {
    throw DdsError("cannot load Fast DDS XML profiles from " + file);
  }
  loaded.insert(file);
}
}  // namespace

HostPort parse_host_port(const std::string& flag, const std::string& text, int default_port) {
  HostPort hp;
  const auto colon = text.rfind(':');
  hp.address = text.substr(0, colon);
  check_ipv4(flag, text, hp.address, "a.b.c.d[:port]");
  hp.port =
      colon == std::string::npos ? default_port : parse_port(flag, text, text.substr(colon + 1));
  return hp;
}

std::map<std::string, std::string> profile_index() {
  std::map<std::string, std::string> index;
  const fs::path dir = profiles_dir();
  if (!fs::is_directory(dir)) return index;
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.path().extension() == ".xml") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  for (const auto& f : files) {
    for (const auto& name : participant_profiles(slurp(f))) index.emplace(name, f.string());
  }
  return index;
}

ProfileRef resolve_profile(const std::string& profile) {
  if (profile.find('/') != std::string::npos || profile.ends_with(".xml")) {
    if (!fs::is_regular_file(profile)) {
      throw config::ConfigError("--profile '" + profile + "': file does not exist");
    }
    const auto names = participant_profiles(slurp(profile));
    const std::string stem = fs::path(profile).stem().string();
    if (std::find(names.begin(), names.end(), stem) != names.end()) return {profile, stem};
    if (names.size() == 1) return {profile, names.front()};
    throw config::ConfigError("--profile '" + profile + "': the file defines " +
                              (names.empty() ? std::string("no participant profile")
                                             : "participant profiles {" + join(names) +
                                                   "}; give one by name with TELEOP_PROFILES_DIR"));
  }
  const auto index = profile_index();
  const auto it = index.find(profile);
  if (it == index.end()) {
    throw config::ConfigError("--profile '" + profile +
                              "': no participant profile of that name in " + profiles_dir() +
                              "/*.xml; available profiles: {" + join(available_profiles()) + "}");
  }
  return {it->second, profile};
}

std::string profile_file(const std::string& profile) { return resolve_profile(profile).file; }

SecurityFiles security_files(const SecurityOptions& s) {
  static const std::regex identity_re("[A-Za-z0-9_][A-Za-z0-9_.-]*");
  if (!std::regex_match(s.identity, identity_re)) {
    throw config::ConfigError(
        (s.identity_source.empty() ? std::string("identity") : s.identity_source) + " '" +
        s.identity +
        "' is not an identity name (letters, digits, _ . -; e.g. server, master, "
        "observer)");
  }
  std::error_code ec;
  if (s.dir.empty()) throw config::ConfigError("--security-dir: empty path");
  if (!fs::is_directory(s.dir, ec)) {
    throw config::ConfigError(security_dir_label(s) + ": " +
                              (fs::exists(s.dir, ec) ? "not a directory" : "no such directory") +
                              " (make one with deploy/make_security.sh DIR; docs/networking.md)");
  }
  const fs::path dir = fs::absolute(s.dir, ec);
  const fs::path id = dir / s.identity;
  if (!fs::is_directory(id, ec)) {
    std::vector<std::string> have;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
      if (e.is_directory() && fs::exists(e.path() / "identity.cert.pem")) {
        have.push_back(e.path().filename().string());
      }
    }
    std::sort(have.begin(), have.end());
    throw config::ConfigError(
        security_dir_label(s) + ": no identity '" + s.identity + "' (missing folder " +
        id.string() + " with identity.cert.pem, identity.key.pem, permissions.p7s); identities " +
        "there: {" + join(have) + "}; choose one with --identity NAME (or TELEOP_IDENTITY)");
  }
  SecurityFiles f;
  f.identity_ca = (dir / "identity_ca.cert.pem").string();
  f.permissions_ca = (dir / "permissions_ca.cert.pem").string();
  f.governance = (dir / "governance.p7s").string();
  f.identity_certificate = (id / "identity.cert.pem").string();
  f.private_key = (id / "identity.key.pem").string();
  f.permissions = (id / "permissions.p7s").string();
  const std::string pem_cert = "-----BEGIN CERTIFICATE-----";
  check_security_file(s, f.identity_ca, "the identity CA certificate", pem_cert,
                      "a PEM certificate, " + pem_cert);
  check_security_file(s, f.permissions_ca, "the permissions CA certificate", pem_cert,
                      "a PEM certificate, " + pem_cert);
  check_security_file(s, f.governance, "the governance document signed by the permissions CA",
                      "pkcs7-signature", "an S/MIME signed document: openssl smime -sign");
  check_security_file(s, f.identity_certificate, "the identity certificate of '" + s.identity + "'",
                      pem_cert, "a PEM certificate, " + pem_cert);
  check_security_file(s, f.private_key, "the private key of '" + s.identity + "'",
                      "PRIVATE KEY-----", "a PEM private key, -----BEGIN ... PRIVATE KEY-----");
  check_security_file(s, f.permissions,
                      "the permissions of '" + s.identity + "' signed by the permissions CA",
                      "pkcs7-signature", "an S/MIME signed document: openssl smime -sign");
  return f;
}

bool is_secure(const DomainParticipantQos& qos) {
  const auto* auth = eprosima::fastrtps::rtps::PropertyPolicyHelper::find_property(
      qos.properties(), "dds.sec.auth.plugin");
  return auth != nullptr && !auth->empty();
}

namespace {

/// Every UDPv4 transport of `qos` expands each initial peer without a port to the ports of
/// participant ids 0 .. kWholeDomainPeers - 1, fewer where the last ids' ports of `domain` would
/// pass 65535 (copies: the XML's descriptors stay intact).
void widen_initial_peers(DomainParticipantQos& qos, int domain) {
  using eprosima::fastdds::rtps::UDPv4TransportDescriptor;
  const int user_port_of_id0 = 7411 + 250 * domain;  // the highest port of participant id 0
  const int ids = std::min(kWholeDomainPeers, (65535 - user_port_of_id0) / 2 + 1);
  for (auto& t : qos.transport().user_transports) {
    auto old = std::dynamic_pointer_cast<UDPv4TransportDescriptor>(t);
    if (!old || old->maxInitialPeersRange >= static_cast<uint32_t>(ids)) continue;
    auto d = std::make_shared<UDPv4TransportDescriptor>(*old);
    d->maxInitialPeersRange = static_cast<uint32_t>(ids);
    t = d;
  }
}

}  // namespace

bool reaches_beyond_loopback(const DomainParticipantQos& qos) {
  using eprosima::fastdds::rtps::SharedMemTransportDescriptor;
  using eprosima::fastdds::rtps::UDPv4TransportDescriptor;
  if (qos.transport().use_builtin_transports) return true;
  for (const auto& t : qos.transport().user_transports) {
    if (std::dynamic_pointer_cast<SharedMemTransportDescriptor>(t)) continue;
    auto u = std::dynamic_pointer_cast<UDPv4TransportDescriptor>(t);
    if (!u) return true;  // TCP, or a transport this check does not know
    if (u->interfaceWhiteList.size() != 1 || u->interfaceWhiteList[0] != "127.0.0.1") return true;
  }
  return false;
}

namespace {

/// True when environment variable `name` is 1, true or yes.
bool env_flag(const char* name) {
  const char* v = std::getenv(name);
  if (!v) return false;
  const std::string s = v;
  return s == "1" || s == "true" || s == "yes";
}

/// A profile that reaches beyond 127.0.0.1 without DDS Security needs --insecure: refused
/// without it (naming the secure profiles), announced on stderr with it.
void check_open_profile(ParticipantOptions& o, const DomainParticipantQos& qos, bool accepted) {
  if (is_secure(qos) || !reaches_beyond_loopback(qos)) return;
  const std::string profile = resolve_profile(o.profile).name;
  if (!accepted) {
    throw config::ConfigError(
        "profile '" + profile +
        "' reaches beyond 127.0.0.1 without DDS Security: any host on the network could read "
        "every topic and command the slave. Use a secure profile (" +
        secure_profile_names() +
        ") with --security-dir DIR, or accept it with --insecure (or TELEOP_INSECURE=1)");
  }
  o.insecure = true;
  std::fprintf(stderr,
               "%s: warning: INSECURE: profile '%s' without DDS Security (--insecure): any host "
               "on the network can read every topic and command the slave\n",
               o.name.c_str(), profile.c_str());
}

}  // namespace

namespace {

/// The QoS of participant profile `ref` as its XML file gives it.
DomainParticipantQos profile_qos(const ProfileRef& ref) {
  load_once(ref.file);
  DomainParticipantQos qos;
  if (DomainParticipantFactory::get_instance()->get_participant_qos_from_profile(ref.name, qos) !=
      ReturnCode_t::RETCODE_OK) {
    throw DdsError("profile '" + ref.name + "' not found in " + ref.file);
  }
  return qos;
}

/// Discovery client, TCP or UDP, from the profile's discovery protocol and transports;
/// `loopback_only` is set when a UDP transport is bound to 127.0.0.1 alone.
ProfileKind profile_kind(const DomainParticipantQos& qos, bool& loopback_only) {
  using namespace eprosima::fastrtps::rtps;
  using eprosima::fastdds::rtps::TCPv4TransportDescriptor;
  using eprosima::fastdds::rtps::UDPv4TransportDescriptor;
  bool tcp = false;
  loopback_only = false;
  for (const auto& t : qos.transport().user_transports) {
    if (std::dynamic_pointer_cast<TCPv4TransportDescriptor>(t)) tcp = true;
    if (auto u = std::dynamic_pointer_cast<UDPv4TransportDescriptor>(t)) {
      loopback_only = loopback_only || (u->interfaceWhiteList.size() == 1 &&
                                        u->interfaceWhiteList[0] == "127.0.0.1");
    }
  }
  const auto protocol = qos.wire_protocol().builtin.discovery_config.discoveryProtocol;
  return (protocol == DiscoveryProtocol_t::CLIENT || protocol == DiscoveryProtocol_t::SUPER_CLIENT)
             ? ProfileKind::kDiscoveryClient
             : (tcp ? ProfileKind::kTcp : ProfileKind::kUdp);
}

/// " does not apply to profile 'NAME'": the tail of the errors for an option a profile refuses.
std::string not_in_profile(const std::string& profile) {
  return " does not apply to profile '" + profile + "'";
}

/// --listen, --public-address and --discovery-server refused by a profile of the wrong kind.
void check_network_options_fit(ProfileKind kind, const NetworkOptions& net,
                               const std::string& profile) {
  const std::string in_profile = not_in_profile(profile);
  if (kind != ProfileKind::kTcp && net.listen_port != 0) {
    throw config::ConfigError("--listen " + std::to_string(net.listen_port) + in_profile +
                              " (TCP profiles only: wan_tcp_server, wan_tcp_client)");
  }
  if (kind != ProfileKind::kTcp && !net.public_address.empty()) {
    throw config::ConfigError("--public-address " + net.public_address + in_profile +
                              " (TCP profiles only: wan_tcp_server, wan_tcp_client)");
  }
  if (kind != ProfileKind::kDiscoveryClient && !net.discovery_servers.empty()) {
    throw config::ConfigError("--discovery-server " + net.discovery_servers[0].address +
                              in_profile + " (use --profile discovery_client)");
  }
}

/// A secure profile gets the DDS Security file properties of `sec` (which must name a
/// folder); an open one refuses --security-dir and --identity.
void apply_security(DomainParticipantQos& qos, const SecurityOptions& sec,
                    const std::string& profile) {
  if (!is_secure(qos)) {
    if (!sec.dir.empty()) {
      throw config::ConfigError(security_dir_label(sec) + not_in_profile(profile) +
                                " (secure profiles only: " + secure_profile_names() + ")");
    }
    if (!sec.identity_source.empty()) {
      throw config::ConfigError(sec.identity_source + " '" + sec.identity + "'" +
                                not_in_profile(profile) +
                                " (secure profiles only: " + secure_profile_names() + ")");
    }
    return;
  }
  if (sec.dir.empty()) {
    throw config::ConfigError(
        "profile '" + profile +
        "' needs --security-dir DIR (or TELEOP_SECURITY_DIR): the folder made by "
        "deploy/make_security.sh, with identity_ca.cert.pem, permissions_ca.cert.pem, "
        "governance.p7s and IDENTITY/{identity.cert.pem, identity.key.pem, permissions.p7s} "
        "(identity '" +
        sec.identity + "'; another with --identity NAME)");
  }
  const SecurityFiles f = security_files(sec);
  auto& props = qos.properties().properties();
  auto set = [&props](const std::string& name, const std::string& value) {
    for (auto& p : props) {
      if (p.name() == name) {
        p.value() = value;
        return;
      }
    }
    props.emplace_back(name, value);
  };
  set("dds.sec.auth.builtin.PKI-DH.identity_ca", file_uri(f.identity_ca));
  set("dds.sec.auth.builtin.PKI-DH.identity_certificate", file_uri(f.identity_certificate));
  set("dds.sec.auth.builtin.PKI-DH.private_key", file_uri(f.private_key));
  set("dds.sec.access.builtin.Access-Permissions.permissions_ca", file_uri(f.permissions_ca));
  set("dds.sec.access.builtin.Access-Permissions.governance", file_uri(f.governance));
  set("dds.sec.access.builtin.Access-Permissions.permissions", file_uri(f.permissions));
}

/// A UDPv4 locator for `hp`; port 0 stands for the well-known ports of the domain.
eprosima::fastrtps::rtps::Locator_t udp_locator(const HostPort& hp) {
  using namespace eprosima::fastrtps::rtps;
  Locator_t loc;
  loc.kind = LOCATOR_KIND_UDPv4;
  IPLocator::setIPv4(loc, hp.address);
  loc.port = static_cast<uint32_t>(hp.port);  // 0: the well-known ports of the domain
  return loc;
}

/// UDP profiles: --peer addresses as initial peers (refused by a loopback-only profile,
/// required by the unicast ones), widened to the whole domain when asked.
void apply_udp_peers(DomainParticipantQos& qos, const ParticipantOptions& options,
                     const std::string& profile, bool loopback_only) {
  const NetworkOptions& net = options.network;
  if (!net.peers.empty() && loopback_only) {
    throw config::ConfigError("--peer " + net.peers[0].address + not_in_profile(profile) +
                              " (it talks to 127.0.0.1 only; use lan or lan_unicast)");
  }
  if (net.peers.empty() && (profile == "lan_unicast" || profile == "secure_lan_unicast")) {
    throw config::ConfigError("profile '" + profile +
                              "' needs --peer ADDR[:PORT] (or TELEOP_PEERS)"
                              ": the addresses of the other hosts");
  }
  for (const auto& p : net.peers) {
    qos.wire_protocol().builtin.initialPeersList.push_back(udp_locator(p));
  }
  if (options.announce_to_whole_domain) widen_initial_peers(qos, options.domain);
}

/// TCP profiles: each TCP transport copied with the --listen port and --public-address put
/// in; true when one of them listens.
bool apply_tcp_listening(DomainParticipantQos& qos, const NetworkOptions& net) {
  using eprosima::fastdds::rtps::TCPv4TransportDescriptor;
  bool listening = false;
  for (auto& t : qos.transport().user_transports) {
    auto old = std::dynamic_pointer_cast<TCPv4TransportDescriptor>(t);
    if (!old) continue;
    auto d = std::make_shared<TCPv4TransportDescriptor>(*old);  // the XML's stays intact
    if (net.listen_port != 0) d->listening_ports = {static_cast<uint16_t>(net.listen_port)};
    if (!net.public_address.empty()) {
      if (d->listening_ports.empty()) {
        throw config::ConfigError("--public-address " + net.public_address +
                                  " needs a listening port (--listen PORT, or profile "
                                  "wan_tcp_server)");
      }
      d->set_WAN_address(net.public_address);
    }
    listening = listening || !d->listening_ports.empty();
    t = d;
  }
  return listening;
}

/// TCP profiles: the listening port and public address, a participant id of its own for a
/// client that does not listen (which needs --peer), and the --peer servers as initial peers.
void apply_tcp(DomainParticipantQos& qos, const NetworkOptions& net, const std::string& profile) {
  using namespace eprosima::fastrtps::rtps;
  const bool listening = apply_tcp_listening(qos, net);
  if (!listening) {
    // A client that opens no port: Fast DDS 2.9 gives every such participant id 0, so two
    // clients on one host announce the same logical ports and the server has been seen
    // (in CI, about one run in six) to answer only one of them. A participant id of each
    // process's own keeps their logical ports apart (7400 + 250 domain + 10 + 2 id stays
    // below 65536 for every domain up to 232 with ids up to 60).
    qos.wire_protocol().participant_id = 1 + static_cast<int32_t>(getpid() % 60);
  }
  if (!listening && net.peers.empty()) {
    throw config::ConfigError("profile '" + profile +
                              "' needs --peer SERVER_ADDRESS[:PORT] (or TELEOP_PEERS): the "
                              "address of the teleop_server host (port default 5100)");
  }
  for (const auto& p : net.peers) {
    Locator_t loc;
    loc.kind = LOCATOR_KIND_TCPv4;
    IPLocator::setIPv4(loc, p.address);
    IPLocator::setPhysicalPort(loc, static_cast<uint16_t>(p.port ? p.port : kDefaultTcpPort));
    IPLocator::setLogicalPort(loc, 0);  // 0: the logical ports of the domain
    qos.wire_protocol().builtin.initialPeersList.push_back(loc);
  }
}

/// Discovery client profiles: the --discovery-server addresses replace the XML's servers
/// (one of the two is needed); --peer is refused.
void apply_discovery_servers(DomainParticipantQos& qos, const NetworkOptions& net,
                             const std::string& profile) {
  using namespace eprosima::fastrtps::rtps;
  auto& discovery = qos.wire_protocol().builtin.discovery_config;
  if (!net.peers.empty()) {
    throw config::ConfigError("--peer " + net.peers[0].address + not_in_profile(profile) +
                              " (give the servers with --discovery-server)");
  }
  if (net.discovery_servers.empty() && discovery.m_DiscoveryServers.empty()) {
    throw config::ConfigError(
        "profile '" + profile +
        "' needs --discovery-server ADDR[:PORT] (or TELEOP_DISCOVERY_SERVERS), once per "
        "server in server-id order (port default 11811)");
  }
  if (!net.discovery_servers.empty()) discovery.m_DiscoveryServers.clear();
  for (std::size_t i = 0; i < net.discovery_servers.size(); ++i) {
    RemoteServerAttributes server;
    get_server_client_default_guidPrefix(static_cast<int>(i), server.guidPrefix);
    HostPort hp = net.discovery_servers[i];
    if (hp.port == 0) hp.port = kDefaultDiscoveryPort;
    server.metatrafficUnicastLocatorList.push_back(udp_locator(hp));
    discovery.m_DiscoveryServers.push_back(server);
  }
}

}  // namespace

DomainParticipantQos participant_qos(const ParticipantOptions& options, ProfileKind* kind_out) {
  const ProfileRef ref = resolve_profile(options.profile);
  DomainParticipantQos qos = profile_qos(ref);
  qos.name(options.name);
  bool loopback_only = false;
  const ProfileKind kind = profile_kind(qos, loopback_only);
  if (kind_out) *kind_out = kind;

  check_network_options_fit(kind, options.network, ref.name);
  apply_security(qos, options.network.security, ref.name);
  switch (kind) {
    case ProfileKind::kUdp:
      apply_udp_peers(qos, options, ref.name, loopback_only);
      break;
    case ProfileKind::kTcp:
      apply_tcp(qos, options.network, ref.name);
      break;
    case ProfileKind::kDiscoveryClient:
      apply_discovery_servers(qos, options.network, ref.name);
      break;
  }
  return qos;
}

ParticipantOptions resolve_participant_options(const std::optional<std::string>& profile_flag,
                                               const std::optional<int>& domain_flag,
                                               const std::string& name, const NetworkFlags& net) {
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
  // network options: flag > environment; a bad value names the flag or the variable
  if (!net.peers.empty()) {
    for (const auto& p : net.peers) o.network.peers.push_back(parse_host_port("--peer", p, 0));
  } else if (const char* env = env_or_null("TELEOP_PEERS")) {
    for (const auto& p : split_list(env)) {
      o.network.peers.push_back(parse_host_port("TELEOP_PEERS", p, 0));
    }
  }
  if (net.listen) {
    o.network.listen_port = parse_port("--listen", *net.listen, *net.listen);
  } else if (const char* env = env_or_null("TELEOP_LISTEN_PORT")) {
    o.network.listen_port = parse_port("TELEOP_LISTEN_PORT", env, env);
  }
  if (net.public_address) {
    check_ipv4("--public-address", *net.public_address, *net.public_address, "a.b.c.d");
    o.network.public_address = *net.public_address;
  } else if (const char* env = env_or_null("TELEOP_PUBLIC_ADDRESS")) {
    check_ipv4("TELEOP_PUBLIC_ADDRESS", env, env, "a.b.c.d");
    o.network.public_address = env;
  }
  if (!net.discovery_servers.empty()) {
    for (const auto& p : net.discovery_servers) {
      o.network.discovery_servers.push_back(
          parse_host_port("--discovery-server", p, kDefaultDiscoveryPort));
    }
  } else if (const char* env = env_or_null("TELEOP_DISCOVERY_SERVERS")) {
    for (const auto& p : split_list(env)) {
      o.network.discovery_servers.push_back(
          parse_host_port("TELEOP_DISCOVERY_SERVERS", p, kDefaultDiscoveryPort));
    }
  }
  // security: flag > environment; the identity defaults to the executable's role
  SecurityOptions& sec = o.network.security;
  if (net.security_dir) {
    sec.dir = *net.security_dir;
    sec.dir_source = "--security-dir";
  } else if (const char* env = env_or_null("TELEOP_SECURITY_DIR")) {
    sec.dir = env;
    sec.dir_source = "TELEOP_SECURITY_DIR";
  }
  if (net.identity) {
    sec.identity = *net.identity;
    sec.identity_source = "--identity";
  } else if (const char* env = env_or_null("TELEOP_IDENTITY")) {
    sec.identity = env;
    sec.identity_source = "TELEOP_IDENTITY";
  } else {
    sec.identity = net.default_identity;
  }
  // fail early: unknown profile, options that do not fit it
  check_open_profile(o, participant_qos(o), net.insecure || env_flag("TELEOP_INSECURE"));
  return o;
}

Participant::Participant(const ParticipantOptions& options) : options_(options) {
  install_log_summary();  // Fast DDS's repeated error lines: once, then a count
  auto* factory = DomainParticipantFactory::get_instance();
  const DomainParticipantQos qos = participant_qos(options);
  participant_ = factory->create_participant(static_cast<DomainId_t>(options.domain), qos);
  if (!participant_) {
    const ProfileRef ref = resolve_profile(options.profile);
    std::string why;
    if (is_secure(qos)) {
      const SecurityOptions& s = options.network.security;
      std::string reason;
      try {
        reason = diagnose_security_files(security_files(s));
      } catch (const std::exception& e) {
        reason = e.what();
      }
      if (!reason.empty()) {
        why = ": DDS Security refused identity '" + s.identity + "' of " + security_dir_label(s) +
              ": " + reason;
      } else {
        // the files pass the checks made here: the cause is Fast DDS's line above, a transport
        // or profile setting as well as what these checks cannot see in the security files
        why = ": Fast DDS's own error is printed above (identity '" + s.identity + "' of " +
              security_dir_label(s) +
              " passes the file checks made here; if that error is DDS Security's: the "
              "certificate must be signed by identity_ca.cert.pem and match its key, "
              "governance.p7s and its permissions.p7s must be signed by permissions_ca.cert.pem, "
              "the permissions must name the certificate's subject, be valid now and allow "
              "domain " +
              std::to_string(options.domain) + ")";
      }
    } else {
      why = ": Fast DDS's own error is printed above";
    }
    throw DdsError("cannot create a DDS participant with profile '" + ref.name + "' from " +
                   ref.file + " on domain " + std::to_string(options.domain) + why);
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
  flush_log_summary();
}

Topic* Participant::topic(const std::string& topic_name, TypeSupport type) {
  auto it = topics_.find(topic_name);
  if (it != topics_.end()) return it->second;
  const std::string& type_name = type.get_type_name();
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
    case TopicQos::kLatest:
      // best effort: no acknowledgements from every observer back to the writer's process.
      // Volatile: a Fast DDS 2.9 best-effort writer does not send its history to a late reader
      // (rate_limited_publisher_test), so transient local would promise nothing; a late
      // observer gets the next copy, at most one period (17 / 100 ms) after it matched.
      q.reliability().kind = BEST_EFFORT_RELIABILITY_QOS;
      q.durability().kind = VOLATILE_DURABILITY_QOS;
      q.history().kind = KEEP_LAST_HISTORY_QOS;
      q.history().depth = 1;
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
