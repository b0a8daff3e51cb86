// Profile names resolve to (file, participant profile) pairs, whatever the file is called, and
// the network flags are parsed, checked against the profile and put into the participant QoS.
#include <gtest/gtest.h>

#include <fastdds/rtps/attributes/PropertyPolicy.h>
#include <fastdds/rtps/transport/TCPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "common/config/config.hpp"
#include "common/dds/participant.hpp"
#include "common/util/data_dir.hpp"

namespace teleop::dds {
namespace {

using eprosima::fastrtps::rtps::IPLocator;

void clear_env() {
  for (const char* v : {"TELEOP_PROFILE", "TELEOP_DOMAIN", "TELEOP_PEERS", "TELEOP_LISTEN_PORT",
                        "TELEOP_PUBLIC_ADDRESS", "TELEOP_DISCOVERY_SERVERS", "TELEOP_SECURITY_DIR",
                        "TELEOP_IDENTITY", "TELEOP_INSECURE"}) {
    unsetenv(v);
  }
}

NetworkFlags insecure() {
  NetworkFlags f;
  f.insecure = true;
  return f;
}
NetworkFlags peers(std::vector<std::string> v) {
  NetworkFlags f;
  f.insecure = true;  // these profiles reach beyond 127.0.0.1 without DDS Security
  f.peers = std::move(v);
  return f;
}
NetworkFlags listen(const std::string& port, const std::string& public_address = "") {
  NetworkFlags f;
  f.insecure = true;  // these profiles reach beyond 127.0.0.1 without DDS Security
  f.listen = port;
  if (!public_address.empty()) f.public_address = public_address;
  return f;
}
NetworkFlags public_address(const std::string& a) {
  NetworkFlags f;
  f.insecure = true;  // these profiles reach beyond 127.0.0.1 without DDS Security
  f.public_address = a;
  return f;
}
NetworkFlags servers(std::vector<std::string> v) {
  NetworkFlags f;
  f.insecure = true;  // these profiles reach beyond 127.0.0.1 without DDS Security
  f.discovery_servers = std::move(v);
  return f;
}

/// A folder laid out as deploy/make_security.sh's with files that only look right (the checks
/// before DDS starts read markers, not signatures): identities server, master, observer.
std::string fake_security_dir() {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("teleop_fake_sec_" + std::to_string(getpid()));
  fs::remove_all(dir);
  const std::string cert = "-----BEGIN CERTIFICATE-----\nx\n-----END CERTIFICATE-----\n";
  const std::string smime = "Content-Type: multipart/signed; application/x-pkcs7-signature\n";
  fs::create_directories(dir);
  std::ofstream(dir / "identity_ca.cert.pem") << cert;
  std::ofstream(dir / "permissions_ca.cert.pem") << cert;
  std::ofstream(dir / "governance.p7s") << smime;
  for (const char* id : {"server", "master", "observer"}) {
    fs::create_directories(dir / id);
    std::ofstream(dir / id / "identity.cert.pem") << cert;
    std::ofstream(dir / id / "identity.key.pem") << "-----BEGIN EC PRIVATE KEY-----\nx\n";
    std::ofstream(dir / id / "permissions.p7s") << smime;
  }
  return dir.string();
}

/// The message of the ConfigError `f` throws ("" if none).
template <class F>
std::string error_of(F f) {
  try {
    f();
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(ProfileLookup, EveryDocumentedNameResolvesToItsFile) {
  const std::map<std::string, std::string> expected = {
      {"loopback", "loopback.xml"},
      {"loopback_shm", "loopback_shm.xml"},
      {"lan", "lan.xml"},
      {"lan_unicast", "lan.xml"},
      {"wan_tcp_server", "wan_tcp.xml"},
      {"wan_tcp_client", "wan_tcp.xml"},
      {"discovery_client", "discovery_server.xml"},
      {"secure", "secure.xml"},
      {"secure_lan", "secure.xml"},
      {"secure_lan_unicast", "secure.xml"},
      {"secure_wan_tcp_server", "secure_wan_tcp.xml"},
      {"secure_wan_tcp_client", "secure_wan_tcp.xml"}};
  const auto index = profile_index();
  for (const auto& [name, file] : expected) {
    const ProfileRef ref = resolve_profile(name);
    EXPECT_EQ(ref.name, name);
    EXPECT_TRUE(ref.file.ends_with("deploy/profiles/" + file)) << name << " -> " << ref.file;
    EXPECT_EQ(index.count(name), 1u) << name;
  }
  // and nothing undocumented: every profile of the folder is in the table above
  for (const auto& [name, file] : index) EXPECT_EQ(expected.count(name), 1u) << name;
}

TEST(ProfileLookup, AFileBaseNameIsNotAProfileName) {
  // wan_tcp.xml holds wan_tcp_server and wan_tcp_client, not "wan_tcp"
  const std::string msg = error_of([] { resolve_profile("wan_tcp"); });
  EXPECT_NE(msg.find("--profile 'wan_tcp'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("wan_tcp_server"), std::string::npos) << msg;
  EXPECT_NE(msg.find("discovery_client"), std::string::npos) << msg;
}

TEST(ProfileLookup, AnXmlPathUsesTheProfileNamedLikeTheFileOrItsOnlyOne) {
  const std::string dir = teleop::data_path("profiles");
  EXPECT_EQ(resolve_profile(dir + "/loopback.xml").name, "loopback");
  EXPECT_EQ(resolve_profile(dir + "/discovery_server.xml").name, "discovery_client");
  const std::string msg = error_of([&] { resolve_profile(dir + "/wan_tcp.xml"); });
  EXPECT_NE(msg.find("wan_tcp_client"), std::string::npos) << msg;
  EXPECT_NE(error_of([] { resolve_profile("/nonexistent/x.xml"); }).find("does not exist"),
            std::string::npos);
}

TEST(ProfileLookup, EveryProfileGivesAParticipantQos) {
  clear_env();
  const std::string sec = fake_security_dir();
  for (const auto& [name, file] : profile_index()) {
    ParticipantOptions o{name, 0, "t"};
    if (name.ends_with("lan_unicast") || name.ends_with("wan_tcp_client")) {
      o.network.peers = {{"10.1.2.3", 0}};
    }
    if (name == "discovery_client") o.network.discovery_servers = {{"10.1.2.3", 11811}};
    if (name.starts_with("secure")) o.network.security = {sec, "--security-dir", "master", ""};
    EXPECT_NO_THROW(participant_qos(o)) << name;
    EXPECT_EQ(is_secure(participant_qos(o)), name.starts_with("secure")) << name;
  }
  std::filesystem::remove_all(sec);
}

TEST(SecurityFlags, SecureProfilesGetTheFilesOfTheIdentityAsPluginProperties) {
  clear_env();
  const std::string sec = fake_security_dir();
  NetworkFlags f;
  f.security_dir = sec;
  f.default_identity = "master";
  auto o = resolve_participant_options("secure", 5, "t", f);
  EXPECT_EQ(o.network.security.identity, "master");
  const auto qos = participant_qos(o);
  auto prop = [&](const std::string& n) {
    const auto* v =
        eprosima::fastrtps::rtps::PropertyPolicyHelper::find_property(qos.properties(), n);
    return v ? *v : std::string("(none)");
  };
  EXPECT_EQ(prop("dds.sec.auth.plugin"), "builtin.PKI-DH");
  EXPECT_EQ(prop("dds.sec.access.plugin"), "builtin.Access-Permissions");
  EXPECT_EQ(prop("dds.sec.crypto.plugin"), "builtin.AES-GCM-GMAC");
  EXPECT_EQ(prop("dds.sec.auth.builtin.PKI-DH.identity_ca"),
            "file://" + sec + "/identity_ca.cert.pem");
  EXPECT_EQ(prop("dds.sec.auth.builtin.PKI-DH.identity_certificate"),
            "file://" + sec + "/master/identity.cert.pem");
  EXPECT_EQ(prop("dds.sec.auth.builtin.PKI-DH.private_key"),
            "file://" + sec + "/master/identity.key.pem");
  EXPECT_EQ(prop("dds.sec.access.builtin.Access-Permissions.permissions_ca"),
            "file://" + sec + "/permissions_ca.cert.pem");
  EXPECT_EQ(prop("dds.sec.access.builtin.Access-Permissions.governance"),
            "file://" + sec + "/governance.p7s");
  EXPECT_EQ(prop("dds.sec.access.builtin.Access-Permissions.permissions"),
            "file://" + sec + "/master/permissions.p7s");
  // the plain profiles carry no security property at all
  EXPECT_FALSE(is_secure(participant_qos(resolve_participant_options("loopback", 5, "t"))));
  std::filesystem::remove_all(sec);
}

TEST(SecurityFlags, FlagsWinOverTheEnvironmentAndMessagesNameTheSource) {
  clear_env();
  const std::string sec = fake_security_dir();
  setenv("TELEOP_SECURITY_DIR", sec.c_str(), 1);
  setenv("TELEOP_IDENTITY", "observer", 1);
  NetworkFlags f;
  f.default_identity = "server";
  auto o = resolve_participant_options("secure", 5, "t", f);
  EXPECT_EQ(o.network.security.dir, sec);
  EXPECT_EQ(o.network.security.dir_source, "TELEOP_SECURITY_DIR");
  EXPECT_EQ(o.network.security.identity, "observer");
  f.identity = "master";
  EXPECT_EQ(resolve_participant_options("secure", 5, "t", f).network.security.identity, "master");
  // a bad identity from the environment names the variable
  setenv("TELEOP_IDENTITY", "../master", 1);
  std::string m = error_of([] { resolve_participant_options("secure", 5, "t"); });
  EXPECT_NE(m.find("TELEOP_IDENTITY '../master' is not an identity name"), std::string::npos) << m;
  unsetenv("TELEOP_IDENTITY");
  // a plain profile refuses the security variables too, naming them
  m = error_of([] { resolve_participant_options("lan", 5, "t"); });
  EXPECT_NE(m.find("TELEOP_SECURITY_DIR='" + sec + "' does not apply to profile 'lan'"),
            std::string::npos)
      << m;
  unsetenv("TELEOP_SECURITY_DIR");
  NetworkFlags g;
  g.identity = "master";
  m = error_of([&] { resolve_participant_options("loopback", 5, "t", g); });
  EXPECT_NE(m.find("--identity 'master' does not apply to profile 'loopback'"), std::string::npos)
      << m;
  // a secure profile without a folder, and secure_lan_unicast without peers
  m = error_of([] { resolve_participant_options("secure_lan", 5, "t"); });
  EXPECT_NE(m.find("profile 'secure_lan' needs --security-dir DIR"), std::string::npos) << m;
  NetworkFlags h;
  h.security_dir = sec;
  m = error_of([&] { resolve_participant_options("secure_lan_unicast", 5, "t", h); });
  EXPECT_NE(m.find("profile 'secure_lan_unicast' needs --peer"), std::string::npos) << m;
  std::filesystem::remove_all(sec);
}

TEST(NetworkFlags, AddressesAndPortsAreParsed) {
  EXPECT_EQ(parse_host_port("--peer", "10.0.0.2", 0), (HostPort{"10.0.0.2", 0}));
  EXPECT_EQ(parse_host_port("--peer", "10.0.0.2:7000", 0), (HostPort{"10.0.0.2", 7000}));
  EXPECT_EQ(parse_host_port("--discovery-server", "10.0.0.2", 11811),
            (HostPort{"10.0.0.2", 11811}));
}

TEST(NetworkFlags, BadValuesNameTheFlagAndTheValue) {
  clear_env();
  auto err = [](const NetworkFlags& f, const std::string& profile) {
    return error_of([&] { resolve_participant_options(profile, 5, "t", f); });
  };
  std::string m = err(peers({"10.0.0.300:5100"}), "lan");
  EXPECT_NE(m.find("--peer '10.0.0.300:5100'"), std::string::npos) << m;
  EXPECT_NE(m.find("not an IPv4 address"), std::string::npos) << m;
  m = err(peers({"server.example"}), "wan_tcp_client");
  EXPECT_NE(m.find("--peer 'server.example'"), std::string::npos) << m;
  m = err(peers({"10.0.0.1:99999"}), "wan_tcp_client");
  EXPECT_NE(m.find("--peer '10.0.0.1:99999'"), std::string::npos) << m;
  EXPECT_NE(m.find("[1, 65535]"), std::string::npos) << m;
  m = err(peers({"10.0.0.1:"}), "lan");
  EXPECT_NE(m.find("--peer '10.0.0.1:'"), std::string::npos) << m;
  m = err(listen("0"), "wan_tcp_server");
  EXPECT_NE(m.find("--listen '0'"), std::string::npos) << m;
  m = err(listen("51OO"), "wan_tcp_server");
  EXPECT_NE(m.find("--listen '51OO'"), std::string::npos) << m;
  m = err(public_address("1.2.3"), "wan_tcp_server");
  EXPECT_NE(m.find("--public-address '1.2.3'"), std::string::npos) << m;
  m = err(servers({"10.0.0.1:port"}), "discovery_client");
  EXPECT_NE(m.find("--discovery-server '10.0.0.1:port'"), std::string::npos) << m;
}

TEST(NetworkFlags, BadEnvironmentValuesNameTheVariable) {
  clear_env();
  setenv("TELEOP_PEERS", "10.0.0.2,10.0.0.x", 1);
  std::string m = error_of([] { resolve_participant_options("lan", 5, "t"); });
  EXPECT_NE(m.find("TELEOP_PEERS '10.0.0.x'"), std::string::npos) << m;
  clear_env();
  setenv("TELEOP_LISTEN_PORT", "-4", 1);
  m = error_of([] { resolve_participant_options("wan_tcp_server", 5, "t"); });
  EXPECT_NE(m.find("TELEOP_LISTEN_PORT '-4'"), std::string::npos) << m;
  clear_env();
}

TEST(NetworkFlags, OptionsThatDoNotFitTheProfileAreRefused) {
  clear_env();
  auto err = [](const NetworkFlags& f, const std::string& profile) {
    return error_of([&] { resolve_participant_options(profile, 5, "t", f); });
  };
  EXPECT_NE(err(peers({"10.0.0.2"}), "loopback").find("--peer"), std::string::npos);
  EXPECT_NE(err(listen("5100"), "lan").find("--listen 5100 does not apply"), std::string::npos);
  EXPECT_NE(err(servers({"10.0.0.1"}), "lan").find("--discovery-server"), std::string::npos);
  EXPECT_NE(err({}, "wan_tcp_client").find("needs --peer"), std::string::npos);
  EXPECT_NE(err({}, "lan_unicast").find("needs --peer"), std::string::npos);
  EXPECT_NE(err({}, "discovery_client").find("needs --discovery-server"), std::string::npos);
  EXPECT_NE(err(public_address("1.2.3.4"), "wan_tcp_client").find("listening port"),
            std::string::npos);
}

TEST(NetworkFlags, OpenProfilesNeedInsecure) {
  clear_env();
  // refused without --insecure, naming the profile and the secure alternatives
  for (const std::string profile : {"lan", "wan_tcp_server"}) {
    const std::string m = error_of([&] { resolve_participant_options(profile, 5, "t"); });
    EXPECT_NE(m.find("profile '" + profile + "' reaches beyond 127.0.0.1 without DDS Security"),
              std::string::npos)
        << m;
    EXPECT_NE(m.find("secure_lan"), std::string::npos) << m;
    EXPECT_NE(m.find("--insecure"), std::string::npos) << m;
  }
  // accepted with the flag or TELEOP_INSECURE=1, and marked
  EXPECT_TRUE(resolve_participant_options("lan", 5, "t", insecure()).insecure);
  setenv("TELEOP_INSECURE", "1", 1);
  EXPECT_TRUE(resolve_participant_options("lan", 5, "t").insecure);
  clear_env();
  // loopback profiles need nothing and are not marked, with or without the flag
  EXPECT_FALSE(resolve_participant_options("loopback", 5, "t").insecure);
  EXPECT_FALSE(resolve_participant_options("loopback", 5, "t", insecure()).insecure);
  EXPECT_FALSE(resolve_participant_options("loopback_shm", 5, "t").insecure);
  auto qos = [](const std::string& profile) {
    ParticipantOptions o;
    o.profile = profile;
    return participant_qos(o);
  };
  EXPECT_FALSE(reaches_beyond_loopback(qos("loopback")));
  EXPECT_TRUE(reaches_beyond_loopback(qos("lan")));
}

TEST(NetworkFlags, FlagsWinOverTheEnvironment) {
  clear_env();
  setenv("TELEOP_PEERS", "10.0.0.7", 1);
  auto o = resolve_participant_options("lan", 5, "t", insecure());
  ASSERT_EQ(o.network.peers.size(), 1u);
  EXPECT_EQ(o.network.peers[0].address, "10.0.0.7");
  o = resolve_participant_options("lan", 5, "t", peers({"10.0.0.8", "10.0.0.9"}));
  ASSERT_EQ(o.network.peers.size(), 2u);
  EXPECT_EQ(o.network.peers[1].address, "10.0.0.9");
  clear_env();
}

TEST(NetworkFlags, TcpOptionsReachTheTransport) {
  clear_env();
  using eprosima::fastdds::rtps::TCPv4TransportDescriptor;
  auto o = resolve_participant_options("wan_tcp_server", 5, "t", listen("6200", "192.0.2.10"));
  ProfileKind kind{};
  auto qos = participant_qos(o, &kind);
  EXPECT_EQ(kind, ProfileKind::kTcp);
  std::shared_ptr<TCPv4TransportDescriptor> tcp;
  for (const auto& t : qos.transport().user_transports) {
    if (auto d = std::dynamic_pointer_cast<TCPv4TransportDescriptor>(t)) tcp = d;
  }
  ASSERT_TRUE(tcp);
  EXPECT_EQ(tcp->listening_ports, std::vector<uint16_t>{6200});
  EXPECT_EQ(tcp->get_WAN_address(), "192.0.2.10");
  // the XML's own descriptor is not modified: the default port comes back without --listen
  qos = participant_qos(ParticipantOptions{"wan_tcp_server", 5, "t"});
  for (const auto& t : qos.transport().user_transports) {
    if (auto d = std::dynamic_pointer_cast<TCPv4TransportDescriptor>(t)) tcp = d;
  }
  EXPECT_EQ(tcp->listening_ports, std::vector<uint16_t>{5100});

  o = resolve_participant_options("wan_tcp_client", 5, "t", peers({"192.0.2.10"}));
  qos = participant_qos(o);
  ASSERT_EQ(qos.wire_protocol().builtin.initialPeersList.size(), 1u);
  const auto& loc = *qos.wire_protocol().builtin.initialPeersList.begin();
  EXPECT_EQ(IPLocator::toIPv4string(loc), "192.0.2.10");
  EXPECT_EQ(IPLocator::getPhysicalPort(loc), 5100);
}

TEST(NetworkFlags, DiscoveryServersGetTheIdsOfTheirOrder) {
  clear_env();
  auto o = resolve_participant_options("discovery_client", 5, "t",
                                       servers({"192.0.2.1", "192.0.2.2:12000"}));
  ProfileKind kind{};
  const auto qos = participant_qos(o, &kind);
  EXPECT_EQ(kind, ProfileKind::kDiscoveryClient);
  const auto& servers = qos.wire_protocol().builtin.discovery_config.m_DiscoveryServers;
  ASSERT_EQ(servers.size(), 2u);
  eprosima::fastrtps::rtps::GuidPrefix_t id1;
  eprosima::fastrtps::rtps::get_server_client_default_guidPrefix(1, id1);
  auto it = servers.begin();
  const auto& l0 = *it->metatrafficUnicastLocatorList.begin();
  EXPECT_EQ(IPLocator::toIPv4string(l0), "192.0.2.1");
  EXPECT_EQ(l0.port, 11811u);
  ++it;
  EXPECT_EQ(it->guidPrefix, id1);
  EXPECT_EQ(it->metatrafficUnicastLocatorList.begin()->port, 12000u);
}

}  // namespace
}  // namespace teleop::dds
