// deploy/teleop_launch.sh --dry-run prints the ssh command of every process of a session, with
// the network flags of each profile as docs/networking.md writes them; bad hosts exit 2.
// deploy/teleop_discovery.sh --dry-run prints the discovery server command. Nothing is run.
#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

#include "tests/support/integration.hpp"
#include "tests/support/process.hpp"

namespace teleop::test {
namespace {

const std::string kLaunch = std::string(TELEOP_SOURCE_DIR) + "/deploy/teleop_launch.sh";
const std::string kDiscovery = std::string(TELEOP_SOURCE_DIR) + "/deploy/teleop_discovery.sh";

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

/// Runs the launcher with `args`; returns its stdout lines, expecting exit status `rc`.
std::vector<std::string> launch(std::vector<std::string> args, int rc = 0,
                                std::string* err = nullptr) {
  args.insert(args.begin(), kLaunch);
  Process p("/bin/bash", args, "launch");
  EXPECT_EQ(p.wait_for(20.0), rc) << p.err();
  if (err) *err = p.err();
  return lines(p.out());
}

bool has(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

TEST(Launcher, DryRunLanUnicastGivesEveryProcessTheOtherHosts) {
  const auto l = launch({"--dry-run", "--profile", "lan_unicast", "--server", "10.0.0.1",
                         "--master", "op@10.0.0.2", "--observer", "10.0.0.3", "--domain", "9",
                         "--session", "s9", "--insecure", "--", "--duration", "30"});
  ASSERT_EQ(l.size(), 5u);  // server, observer, master, then the two stops
  // the program runs in the background with its own pid recorded, not a subshell's, in the
  // session's own folder; a live pid already there (another launcher's) is refused
  EXPECT_TRUE(has(l[0], "cd /opt/teleop || exit 1; mkdir -p /tmp/teleop_launch/s9 || exit 1;"))
      << l[0];
  EXPECT_TRUE(has(l[0], "kill -0 $(cat /tmp/teleop_launch/s9/server.pid)")) << l[0];
  EXPECT_TRUE(has(l[0], "nohup build/server/teleop_server")) << l[0];
  EXPECT_TRUE(has(l[0], "> /tmp/teleop_launch/s9/server.log 2>&1")) << l[0];
  EXPECT_TRUE(has(l[0], "& echo $! > /tmp/teleop_launch/s9/server.pid")) << l[0];
  EXPECT_TRUE(has(l[0], "ssh ") && has(l[0], " 10.0.0.1 ")) << l[0];
  EXPECT_TRUE(has(l[0], "build/server/teleop_server --domain 9")) << l[0];
  EXPECT_TRUE(has(l[0], "--profile lan_unicast --peer 10.0.0.2 --peer 10.0.0.3")) << l[0];
  EXPECT_TRUE(has(l[1], " 10.0.0.3 ") && has(l[1], "build/client/teleop_monitor")) << l[1];
  EXPECT_TRUE(has(l[1], "--peer 10.0.0.1 --peer 10.0.0.2")) << l[1];
  EXPECT_TRUE(has(l[2], "ssh -t") && has(l[2], " op@10.0.0.2 ")) << l[2];
  EXPECT_TRUE(has(l[2],
                  "build/client/teleop_master --domain 9 --profile lan_unicast "
                  "--peer 10.0.0.1 --peer 10.0.0.3"))
      << l[2];
  EXPECT_TRUE(has(l[2], "--duration 30")) << l[2];
  // stopped in reverse order: the observer, then the server
  EXPECT_TRUE(has(l[3], "kill") && has(l[3], " 10.0.0.3 ")) << l[3];
  EXPECT_TRUE(has(l[4], "kill") && has(l[4], " 10.0.0.1 ")) << l[4];
}

TEST(Launcher, TwoSessionsOnOneDomainShareNoFile) {
  const std::vector<std::string> a = {"--dry-run", "--profile", "lan",      "--server",
                                      "10.0.0.1",  "--master",  "10.0.0.2", "--domain",
                                      "9",         "--insecure"};
  std::string err1, err2;
  const auto l1 = launch(a, 0, &err1), l2 = launch(a, 0, &err2);
  ASSERT_EQ(l1.size(), 3u);
  ASSERT_EQ(l2.size(), 3u);
  // each launcher names its session (d<domain>-<time>-<pid>) and where its files are
  EXPECT_TRUE(has(err1, "teleop_launch: session d9-")) << err1;
  EXPECT_NE(err1, err2);
  const auto folder = [](const std::string& line) {
    const auto at = line.find("/tmp/teleop_launch/d9-");
    return at == std::string::npos ? std::string()
                                   : line.substr(at, line.find_first_of("/ ", at + 19) - at);
  };
  EXPECT_FALSE(folder(l1[0]).empty()) << l1[0];
  EXPECT_NE(folder(l1[0]), folder(l2[0])) << l1[0] << "\n" << l2[0];
  // the stop kills the pid of its own session's file only
  EXPECT_TRUE(has(l1[2], folder(l1[0]) + "/server.pid")) << l1[2];
  std::string err;
  auto bad = a;
  bad.insert(bad.end(), {"--session", "../x"});
  launch(bad, 2, &err);
  EXPECT_TRUE(has(err, "--session '../x' is not a name")) << err;
  bad = a;
  bad.insert(bad.end(), {"--run-dir", "relative/dir"});
  launch(bad, 2, &err);
  EXPECT_TRUE(has(err, "--run-dir 'relative/dir' is not an absolute path")) << err;
}

TEST(Launcher, DryRunWanTcpAndLan) {
  auto l = launch({"--dry-run", "--profile", "wan_tcp", "--server", "10.0.0.1", "--master",
                   "10.0.0.2", "--observer", "10.0.0.3", "--tcp-port", "6000", "--public-address",
                   "203.0.113.5", "--insecure"});
  ASSERT_GE(l.size(), 3u);
  EXPECT_TRUE(has(l[0], "--profile wan_tcp_server --listen 6000 --public-address 203.0.113.5"))
      << l[0];
  EXPECT_TRUE(has(l[1], "--profile wan_tcp_client --peer 203.0.113.5:6000")) << l[1];
  EXPECT_TRUE(has(l[2], "--profile wan_tcp_client --peer 203.0.113.5:6000")) << l[2];
  l = launch({"--dry-run", "--profile", "lan", "--server", "10.0.0.1", "--master", "10.0.0.2",
              "--insecure"});
  ASSERT_EQ(l.size(), 3u);
  EXPECT_TRUE(has(l[0], "--profile lan --insecure")) << l[0];
  EXPECT_TRUE(has(l[1], "--profile lan --insecure")) << l[1];
  EXPECT_FALSE(has(l[0], "--peer")) << l[0];
  // no DDS Security and no --insecure: refused, naming both ways out
  std::string err;
  launch({"--dry-run", "--profile", "lan", "--server", "10.0.0.1", "--master", "10.0.0.2"}, 2,
         &err);
  EXPECT_TRUE(has(err, "--security-dir DIR")) << err;
  EXPECT_TRUE(has(err, "--insecure")) << err;
}

TEST(Launcher, DryRunWithSecurityDirUsesTheSecureProfiles) {
  auto l = launch({"--dry-run", "--profile", "wan_tcp", "--server", "10.0.0.1", "--master",
                   "10.0.0.2", "--observer", "10.0.0.3", "--security-dir", "/etc/teleop/dds"});
  ASSERT_GE(l.size(), 3u);
  EXPECT_TRUE(has(l[0],
                  "--profile secure_wan_tcp_server --listen 5100 --security-dir "
                  "/etc/teleop/dds"))
      << l[0];
  EXPECT_TRUE(has(l[1],
                  "--profile secure_wan_tcp_client --peer 10.0.0.1:5100 --security-dir "
                  "/etc/teleop/dds"))
      << l[1];
  l = launch({"--dry-run", "--profile", "lan_unicast", "--server", "10.0.0.1", "--master",
              "10.0.0.2", "--security-dir", "/etc/teleop/dds"});
  ASSERT_GE(l.size(), 2u);
  EXPECT_TRUE(has(l[0], "--profile secure_lan_unicast --peer 10.0.0.2")) << l[0];
  EXPECT_TRUE(has(l[0], "--security-dir /etc/teleop/dds")) << l[0];
  std::string err;
  launch({"--dry-run", "--profile", "discovery", "--server", "10.0.0.1", "--master", "10.0.0.2",
          "--security-dir", "/etc/teleop/dds"},
         2, &err);
  EXPECT_TRUE(has(err, "--security-dir '/etc/teleop/dds' does not apply to --profile discovery"))
      << err;
}

TEST(Launcher, DryRunDiscoveryStartsTheServersFirst) {
  const auto l =
      launch({"--dry-run", "--profile", "discovery", "--server", "10.0.0.1", "--master", "10.0.0.2",
              "--backup-discovery", "10.0.0.3", "--discovery-port", "12000", "--insecure"});
  ASSERT_GE(l.size(), 4u);
  EXPECT_TRUE(has(l[0], "deploy/teleop_discovery.sh --id 0 --address 10.0.0.1 --port 12000"))
      << l[0];
  EXPECT_TRUE(has(l[1],
                  "deploy/teleop_discovery.sh --id 1 --address 10.0.0.3 --port 12000 "
                  "--backup"))
      << l[1];
  const std::string servers =
      "--profile discovery_client --discovery-server 10.0.0.1:12000 --discovery-server "
      "10.0.0.3:12000";
  EXPECT_TRUE(has(l[2], "teleop_server") && has(l[2], servers)) << l[2];
  EXPECT_TRUE(has(l[3], "teleop_master") && has(l[3], servers)) << l[3];
}

TEST(Launcher, BadArgumentsExitWith2NamingTheFlag) {
  std::string err;
  launch({"--dry-run", "--profile", "lan", "--server", "10.0.0.1", "--master", "10.0.0.x",
          "--insecure"},
         2, &err);
  EXPECT_TRUE(has(err, "--master '10.0.0.x'")) << err;
  launch({"--dry-run", "--profile", "wan", "--server", "10.0.0.1", "--master", "10.0.0.2"}, 2,
         &err);
  EXPECT_TRUE(has(err, "--profile 'wan'")) << err;
  launch({"--dry-run", "--profile", "wan_tcp", "--server", "10.0.0.1", "--master", "10.0.0.2",
          "--tcp-port", "0", "--insecure"},
         2, &err);
  EXPECT_TRUE(has(err, "--tcp-port '0'")) << err;
}

TEST(DiscoveryScript, DryRunAndBadArguments) {
  Process p("/bin/bash",
            {kDiscovery, "--dry-run", "--id", "1", "--address", "10.0.0.3", "--port", "11900",
             "--backup", "--backup-dir", "/var/tmp/ds"},
            "ds_dry");
  ASSERT_EQ(p.wait_for(20.0), 0) << p.err();
  EXPECT_TRUE(has(p.out(), "cd /var/tmp/ds && ")) << p.out();
  EXPECT_TRUE(has(p.out(), "-i 1 -l 10.0.0.3 -p 11900 -b")) << p.out();
  Process bad("/bin/bash", {kDiscovery, "--dry-run", "--port", "70000"}, "ds_bad");
  EXPECT_EQ(bad.wait_for(20.0), 2);
  EXPECT_TRUE(has(bad.err(), "--port '70000'")) << bad.err();
}

}  // namespace
}  // namespace teleop::test
