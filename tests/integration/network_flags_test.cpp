// Every executable refuses a bad address or port with exit status 2 and a message naming the
// flag (or environment variable) and the value, before it starts DDS; every documented
// profile name is accepted (docs/networking.md).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/support/domains.hpp"
#include "tests/support/integration.hpp"
#include "tests/support/process.hpp"

namespace teleop::test {
namespace {

const std::string kMonitorBinary = std::string(TELEOP_BINARY_DIR) + "/client/teleop_monitor";

/// Every case must fail before DDS starts; should one ever start a non-loopback participant,
/// it runs in an empty network namespace of its own (`unshare -n`, where allowed) so that not
/// even a regression sends a packet.
std::vector<std::string> isolated(const std::string& exe, const std::vector<std::string>& args,
                                  std::string* program) {
  static const bool can_unshare = std::filesystem::exists("/usr/bin/unshare") &&
                                  std::system("/usr/bin/unshare -n true >/dev/null 2>&1") == 0;
  if (!can_unshare) {
    *program = exe;
    return args;
  }
  *program = "/usr/bin/unshare";
  std::vector<std::string> out = {"-n", exe};
  out.insert(out.end(), args.begin(), args.end());
  return out;
}

struct Case {
  std::vector<std::string> args;
  std::string expected;  ///< in stderr
};

TEST(NetworkFlags, BadAddressesAndPortsExitWith2NamingTheFlag) {
  const std::string d = std::to_string(domains::kNetworkFlags);
  const std::vector<Case> cases = {
      {{"--profile", "wan_tcp_client", "--peer", "10.0.0.256"}, "--peer '10.0.0.256'"},
      {{"--profile", "wan_tcp_client", "--peer", "10.0.0.1:65536"}, "--peer '10.0.0.1:65536'"},
      {{"--profile", "wan_tcp_server", "--listen", "port"}, "--listen 'port'"},
      {{"--profile", "wan_tcp_server", "--public-address", "example.org"},
       "--public-address 'example.org'"},
      {{"--profile", "discovery_client", "--discovery-server", "10.0.0.1:0"},
       "--discovery-server '10.0.0.1:0'"},
      {{"--profile", "discovery_client"}, "needs --discovery-server"},
      {{"--profile", "wan_tcp_client"}, "needs --peer"},
      {{"--profile", "lan", "--listen", "5100"}, "--listen 5100 does not apply"},
      {{"--profile", "wan_tcp"}, "available profiles"},
  };
  for (const std::string& exe : {kServerBinary, kMasterBinary, kMonitorBinary}) {
    int k = 0;
    for (const auto& c : cases) {
      std::vector<std::string> args = {"--domain", d};
      args.insert(args.end(), c.args.begin(), c.args.end());
      std::string program;
      const auto argv = isolated(exe, args, &program);
      Process p(program, argv, "netflags" + std::to_string(k++));
      EXPECT_EQ(p.wait_for(20.0), 2) << exe << " " << c.expected << "\n" << p.err();
      EXPECT_NE(p.err().find(c.expected), std::string::npos) << exe << "\n" << p.err();
    }
  }
  setenv("TELEOP_PEERS", "10.0.0.1,10.0.0.x", 1);
  std::string program;
  const auto argv = isolated(kServerBinary, {"--domain", d, "--profile", "lan"}, &program);
  Process p(program, argv, "netflags_env");
  unsetenv("TELEOP_PEERS");
  EXPECT_EQ(p.wait_for(20.0), 2) << p.err();
  EXPECT_NE(p.err().find("TELEOP_PEERS '10.0.0.x'"), std::string::npos) << p.err();
}

}  // namespace
}  // namespace teleop::test
