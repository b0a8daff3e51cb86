// Three hosts for each multi-machine profile: the test builds its own network (network
// namespaces on a private bridge, tests/support/netns.hpp) and runs teleop_server on host 1,
// teleop_master on host 2 and two teleop_monitor observers on host 3, with the profiles exactly
// as docs/networking.md writes them. Nothing is sent outside the namespaces the test creates;
// they are removed at the end, also on failure. Skipped, with the reason, where namespaces
// cannot be created (not root, no iproute2, a container without CAP_SYS_ADMIN).
#include <fcntl.h>
#include <gtest/gtest.h>

#include <sys/file.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <initializer_list>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "tests/support/domains.hpp"
#include "tests/support/integration.hpp"
#include "tests/support/netns.hpp"
#include "tests/support/process.hpp"

namespace teleop::test {
namespace {

const std::string kMonitorBinary = std::string(TELEOP_BINARY_DIR) + "/client/teleop_monitor";
const std::string kDiscoveryScript = std::string(TELEOP_SOURCE_DIR) + "/deploy/teleop_discovery.sh";

/// Largest "<name> <rate> Hz" figure printed by teleop_monitor.
double max_rate(const std::string& out, const std::string& name) {
  double best = 0.0;
  for (std::size_t pos = 0; (pos = out.find(name, pos)) != std::string::npos;) {
    pos += name.size();
    best = std::max(best, std::atof(out.c_str() + pos));
  }
  return best;
}

struct Roles {
  std::string profile_server, profile_client;
  std::vector<std::string> server, master, observer;  ///< extra network flags per role
  bool discovery = false;                             ///< start discovery servers first
  bool lose_discovery_server_0 = false;               ///< stop server 0 before the session
  std::string delay = "";                             ///< one-way delay, e.g. "2ms"
  /// the link carries fewer commands per second than the loop issues (DDS Security over TCP):
  /// the loop keeps its period, the network thread replaces the commands it could not write
  /// (counted), and the session may end degraded for the commands it lost
  bool link_limited = false;
};

class MultiHost : public ::testing::Test {
 protected:
  void SetUp() override {
    // one multi-host session at a time, also under `ctest -j`: each is 6 processes at 1 kHz
    lock_fd_ = open("/tmp/teleop_multi_host_test.lock", O_CREAT | O_RDWR, 0666);
    if (lock_fd_ >= 0) flock(lock_fd_, LOCK_EX);
    lab_ = std::make_unique<NetnsLab>(3);
    if (!lab_->create()) {
      const std::string why = lab_->why();
      lab_.reset();
      std::printf("multi_host_test: SKIPPED: %s\n", why.c_str());
      GTEST_SKIP() << "cannot build the test network: " << why;
    }
  }
  void TearDown() override {
    lab_.reset();                        // kills what is left, deletes the namespaces
    if (lock_fd_ >= 0) close(lock_fd_);  // releases the lock
    lock_fd_ = -1;
  }

  /// A process on host i of the test network.
  std::unique_ptr<Process> on(int i, const std::string& exe, std::vector<std::string> args,
                              const std::string& tag) {
    std::vector<std::string> argv = lab_->exec_prefix(i);
    argv.push_back(exe);
    argv.insert(argv.end(), args.begin(), args.end());
    return std::make_unique<Process>(lab_->ip(), argv, "mh_" + tag);
  }

  /// A main discovery server (id 0) on host 1 and a second one (id 1, --backup) on host 2; the
  /// first is killed at once with r.lose_discovery_server_0.
  void start_discovery_servers(const std::string& name, const Roles& r,
                               std::unique_ptr<Process>& ds0, std::unique_ptr<Process>& ds1) {
    ds0 = on(1, "/bin/bash",
             {kDiscoveryScript, "--id", "0", "--address", NetnsLab::address(1), "--port", "11811"},
             name + "_ds0");
    ds1 = on(2, "/bin/bash",
             {kDiscoveryScript, "--id", "1", "--address", NetnsLab::address(2), "--port", "11811",
              "--backup", "--backup-dir", temp_path("mh", name + "_ds1")},
             name + "_ds1");
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    ASSERT_TRUE(ds0->running()) << ds0->err() << ds0->out();
    ASSERT_TRUE(ds1->running()) << ds1->err() << ds1->out();
    if (r.lose_discovery_server_0) {
      ds0->signal(SIGKILL);
      ASSERT_NE(ds0->wait_for(10.0), -1);
    }
  }

  /// A network delay: tc netem on the master's and the server's veth where the kernel has it
  /// (no flags returned), else the master's user-space delay channel (both directions).
  std::vector<std::string> delay_flags(const std::string& name, const Roles& r) {
    if (r.delay.empty()) return {};
    if (lab_->add_netem_delay(1, r.delay) && lab_->add_netem_delay(2, r.delay)) {
      std::printf("multi_host %s: %s one-way delay from tc netem\n", name.c_str(), r.delay.c_str());
      return {};
    }
    std::printf(
        "multi_host %s: no tc netem here; %s one-way delay from the master's delay channel\n",
        name.c_str(), r.delay.c_str());
    return {"--delay", r.delay};
  }

  /// Two observers on host 3, one after the other a second apart: two clients of a TCP profile
  /// started in the same instant on one host have been seen (once in CI) to leave one of them
  /// never matched.
  std::vector<std::unique_ptr<Process>> start_observers(const std::string& name, const Roles& r,
                                                        const std::string& d) {
    std::vector<std::unique_ptr<Process>> observers;
    for (int k = 0; k < 2; ++k) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1000));
      std::vector<std::string> oargs = {"--domain",   d,    "--profile", r.profile_client,
                                        "--duration", "14", "--period",  "0.5",
                                        "--insecure"};
      oargs.insert(oargs.end(), r.observer.begin(), r.observer.end());
      observers.push_back(on(3, kMonitorBinary, oargs, name + "_obs" + std::to_string(k)));
    }
    return observers;
  }

  /// The master's summary: every command issued, written or counted, received, and its round
  /// trip.
  static void check_master(const std::string& name, const Roles& r, const std::string& m,
                           int master_rc, Process& master) {
    const double issued = json_value(m, "issued");
    const double sent = json_value(m, "sent"), received = json_value(m, "received");
    const double replaced = json_nested(m, "network_threads", "commands_dropped");
    const double p50 = json_nested(m, "rtt_ms", "p50"), p99 = json_nested(m, "rtt_ms", "p99");
    std::printf(
        "multi_host %-16s commands %.0f issued, %.0f written, %.0f replaced unwritten, %.0f "
        "received, rtt p50 %.3f ms p99 %.3f ms\n",
        name.c_str(), issued, sent, replaced, received, p50, p99);
    // the loop issues every command whatever the link carries
    EXPECT_GE(issued, 2900) << m;
    EXPECT_GE(received, 0.99 * sent) << m;
    if (r.link_limited) {
      // every issued command is written or counted as replaced; the link carries at least
      // 400 commands per second; the verdict says stable, or degraded for the lost commands
      EXPECT_GE(sent + replaced, issued - 20) << m;
      EXPECT_GE(sent, 1200) << m;
      EXPECT_TRUE(master_rc == 0 || master_rc == 5) << master_rc << master.err() << m;
      EXPECT_TRUE(json_text(m, "verdict") == "stable" || json_text(m, "verdict") == "degraded")
          << m;
    } else {
      ASSERT_EQ(master_rc, 0) << master.err() << master.out();
      // with a delay, the last commands are still in the channel when the master stops
      EXPECT_GE(sent, 2900) << m;
      EXPECT_EQ(json_text(m, "verdict"), "stable") << m;
    }
    EXPECT_GT(p99, 0.0) << m;
    EXPECT_LT(p99, 100.0) << m;  // generous: a loaded 2-core machine
  }

  /// Each observer got the scene and the 10 Hz state copies (teleop/slave_state_monitor).
  static void check_observers(const std::string& name,
                              const std::vector<std::unique_ptr<Process>>& observers) {
    for (std::size_t k = 0; k < observers.size(); ++k) {
      const std::string out = observers[k]->out();
      EXPECT_NE(out.find("scene 'tool-only'"), std::string::npos)
          << name << " observer " << k << "\n"
          << out << observers[k]->err();
      EXPECT_GT(max_rate(out, "slave_state"), 4.0) << name << " observer " << k;
    }
  }

  void session(const std::string& name, int domain, const Roles& r) {
    const std::string d = std::to_string(domain);
    const std::string master_json = temp_path("mh", name + "_master.json");
    const std::string server_json = temp_path("mh", name + "_server.json");
    std::remove(master_json.c_str());
    std::unique_ptr<Process> ds0, ds1;
    if (r.discovery) {
      ASSERT_NO_FATAL_FAILURE(start_discovery_servers(name, r, ds0, ds1));
    }
    const std::vector<std::string> delay = delay_flags(name, r);
    std::vector<std::string> sargs = {"--domain",
                                      d,
                                      "--profile",
                                      r.profile_server,
                                      "--duration",
                                      "60",
                                      "--quiet",
                                      "--scene",
                                      scene_file("tool_only.yaml"),
                                      "--summary-json",
                                      server_json,
                                      "--insecure"};  // plain profiles in namespaces of its own
    sargs.insert(sargs.end(), r.server.begin(), r.server.end());
    auto server = on(1, kServerBinary, sargs, name + "_server");
    std::vector<std::string> margs = {
        "--domain",       d,           "--profile", r.profile_client, "--samples",
        "3000",           "--homing",  "0.5",       "--wait-server",  "20",
        "--summary-json", master_json, "--quiet",   "--insecure"};
    margs.insert(margs.end(), r.master.begin(), r.master.end());
    margs.insert(margs.end(), delay.begin(), delay.end());
    auto master = on(2, kMasterBinary, margs, name + "_master");
    const std::vector<std::unique_ptr<Process>> observers = start_observers(name, r, d);
    const int master_rc = master->wait_for(60.0);
    for (auto& o : observers) EXPECT_EQ(o->wait_for(30.0), 0) << o->err();
    server->signal(SIGTERM);
    EXPECT_EQ(server->wait_for(20.0), 0) << server->err();
    check_master(name, r, Process::slurp(master_json), master_rc, *master);
    check_observers(name, observers);
    if (ds0) ds0->signal(SIGTERM);
    if (ds1) ds1->signal(SIGTERM);
  }

  /// Whether no process runs in the namespaces of `hosts` within `seconds` (polled).
  bool hosts_empty_within(std::initializer_list<int> hosts, double seconds) {
    for (int t = 0; t < static_cast<int>(seconds / 0.05); ++t) {
      bool empty = true;
      for (int i : hosts) {
        FILE* f = popen((lab_->ip() + " netns pids " + lab_->host(i)).c_str(), "r");
        int pid = 0;
        if (f && std::fscanf(f, "%d", &pid) == 1) empty = false;
        if (f) pclose(f);
      }
      if (empty) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    return false;
  }

  std::unique_ptr<NetnsLab> lab_;
  int lock_fd_ = -1;
};

const std::string kH1 = NetnsLab::address(1), kH2 = NetnsLab::address(2),
                  kH3 = NetnsLab::address(3);

TEST_F(MultiHost, LanMulticastWithDelay) {
  Roles r{"lan", "lan", {}, {}, {}};
  r.delay = "2ms";
  session("lan", domains::kMultiHostLan, r);
}

TEST_F(MultiHost, LanUnicastPeers) {
  session("lan_unicast", domains::kMultiHostLanUnicast,
          Roles{"lan_unicast",
                "lan_unicast",
                {"--peer", kH2, "--peer", kH3},
                {"--peer", kH1, "--peer", kH3},
                {"--peer", kH1, "--peer", kH2}});
}

TEST_F(MultiHost, WanTcp) {
  session("wan_tcp", domains::kMultiHostWanTcp,
          Roles{"wan_tcp_server",
                "wan_tcp_client",
                {"--listen", "5100", "--public-address", kH1},
                {"--peer", kH1 + ":5100"},
                {"--peer", kH1 + ":5100"}});
}

/// DDS Security files for a secure multi-host session (deploy/make_security.sh into a temporary
/// folder; removed by the caller). Empty if the script failed.
std::string make_security_dir(const std::string& name) {
  const std::string dir = temp_path("mh", name + "_certs");
  std::filesystem::remove_all(dir);
  const std::string cmd = "bash '" + std::string(TELEOP_SOURCE_DIR) +
                          "/deploy/make_security.sh' --no-other '" + dir + "' > /dev/null 2>&1";
  return std::system(cmd.c_str()) == 0 ? dir : std::string();
}

TEST_F(MultiHost, SecureLanUnicastPeers) {
  const std::string sec = make_security_dir("secure_lan_unicast");
  ASSERT_FALSE(sec.empty()) << "deploy/make_security.sh failed";
  session("secure_lan_unicast", domains::kMultiHostSecureLanUnicast,
          Roles{"secure_lan_unicast",
                "secure_lan_unicast",
                {"--peer", kH2, "--peer", kH3, "--security-dir", sec},
                {"--peer", kH1, "--peer", kH3, "--security-dir", sec},
                {"--peer", kH1, "--peer", kH2, "--security-dir", sec}});
  std::filesystem::remove_all(sec);
}

TEST_F(MultiHost, SecureWanTcp) {
  const std::string sec = make_security_dir("secure_wan_tcp");
  ASSERT_FALSE(sec.empty()) << "deploy/make_security.sh failed";
  Roles r{"secure_wan_tcp_server",
          "secure_wan_tcp_client",
          {"--listen", "5100", "--public-address", kH1, "--security-dir", sec},
          {"--peer", kH1 + ":5100", "--security-dir", sec},
          {"--peer", kH1 + ":5100", "--security-dir", sec}};
  r.link_limited = true;
  session("secure_wan_tcp", domains::kMultiHostSecureWanTcp, r);
  std::filesystem::remove_all(sec);
}

TEST_F(MultiHost, DiscoveryServerWithASecondServer) {
  const std::vector<std::string> servers = {"--discovery-server", kH1 + ":11811",
                                            "--discovery-server", kH2 + ":11811"};
  session("discovery", domains::kMultiHostDiscovery,
          Roles{"discovery_client", "discovery_client", servers, servers, servers, true});
}

TEST_F(MultiHost, DiscoveryServerBackupAloneIsEnough) {
  // server 0 is gone before anyone starts: everything is discovered through server 1
  const std::vector<std::string> servers = {"--discovery-server", kH1 + ":11811",
                                            "--discovery-server", kH2 + ":11811"};
  Roles r{"discovery_client", "discovery_client", servers, servers, servers, true};
  r.lose_discovery_server_0 = true;
  session("discovery_1only", domains::kMultiHostDiscoveryBackup, r);
}

// deploy/teleop_launch.sh for real, with ssh replaced by tests/support/netns_ssh.sh (runs the
// remote command in the namespace of the host's address): discovery servers 0 (server host)
// and 1 (--backup-discovery, host 3), server, two observers, the master in the foreground;
// when the master ends the launcher stops everything it started.
TEST_F(MultiHost, LauncherStartsAndStopsASessionOnThreeHosts) {
  const std::string d = std::to_string(domains::kMultiHostLauncher);
  const std::string master_json = temp_path("mh", "launch_master.json");
  std::remove(master_json.c_str());
  const std::string run_dir = temp_path("mh", "launch_run");
  std::filesystem::remove_all(run_dir);
  const std::string log_prefix = run_dir + "/mh" + d + "/observer";
  const std::string map =
      kH1 + "=" + lab_->host(1) + "," + kH2 + "=" + lab_->host(2) + "," + kH3 + "=" + lab_->host(3);
  setenv("TELEOP_NETNS_MAP", map.c_str(), 1);
  setenv("TELEOP_IP", lab_->ip().c_str(), 1);
  Process launch("/bin/bash",
                 {std::string(TELEOP_SOURCE_DIR) + "/deploy/teleop_launch.sh",
                  "--insecure",
                  "--profile",
                  "discovery",
                  "--server",
                  kH1,
                  "--master",
                  kH2,
                  "--observer",
                  kH3,
                  "--observer",
                  kH3,
                  "--backup-discovery",
                  kH3,
                  "--domain",
                  d,
                  "--remote-dir",
                  TELEOP_SOURCE_DIR,
                  "--build-dir",
                  TELEOP_BINARY_DIR,
                  "--scene",
                  scene_file("tool_only.yaml"),
                  "--ssh",
                  std::string(TELEOP_SOURCE_DIR) + "/tests/support/netns_ssh.sh",
                  "--session",
                  "mh" + d,
                  "--run-dir",
                  run_dir,
                  "--",
                  "--samples",
                  "3000",
                  "--homing",
                  "0.5",
                  "--summary-json",
                  master_json,
                  "--quiet"},
                 "mh_launch");
  unsetenv("TELEOP_NETNS_MAP");
  unsetenv("TELEOP_IP");
  ASSERT_EQ(launch.wait_for(90.0), 0) << launch.err() << launch.out();
  const std::string m = Process::slurp(master_json);
  const double sent = json_value(m, "sent"), received = json_value(m, "received");
  std::printf(
      "multi_host launcher (discovery) commands %.0f/%.0f received, rtt p50 %.3f ms p99 "
      "%.3f ms\n",
      received, sent, json_nested(m, "rtt_ms", "p50"), json_nested(m, "rtt_ms", "p99"));
  // every cycle (and the force's fade-out) issued a command: written, or replaced by a newer
  // one in the network thread's ring when it fell behind on this loaded machine (counted)
  const double replaced = json_nested(m, "network_threads", "commands_dropped");
  const double issued = 3000 + json_value(m, "closing_cycles");
  EXPECT_EQ(sent + replaced, issued) << m;
  EXPECT_LE(replaced, 0.01 * issued) << m;
  EXPECT_GE(received, 0.99 * sent) << m;
  EXPECT_EQ(json_text(m, "verdict"), "stable") << m;
  for (int k = 0; k < 2; ++k) {
    const std::string out = Process::slurp(log_prefix + std::to_string(k) + ".log");
    EXPECT_NE(out.find("scene 'tool-only'"), std::string::npos) << out;
  }
  // the launcher stopped what it started: nothing is left running on hosts 1 and 3
  EXPECT_TRUE(hosts_empty_within({1, 3}, 10.0))
      << "processes left in the namespaces after the launcher ended";
}

}  // namespace
}  // namespace teleop::test
