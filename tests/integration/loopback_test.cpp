// Multi-process tests over loopback DDS: real teleop_server and teleop_master processes,
// each test on a domain id of its own (tests/support/domains.hpp).
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include "common/dds/endpoint.hpp"
#include "common/util/clock.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"
#include "tests/support/domains.hpp"
#include "tests/support/integration.hpp"
#include "tests/support/process.hpp"

namespace teleop::test {
namespace {

// the network tests use the light tool-only scene; experiment 3 uses the default scene
const std::string kToolScene = scene_file("tool_only.yaml");

std::string tmp(const std::string& name) { return temp_path("it", name); }

TEST(Loopback, ServerAndMasterRoundTrip2000CommandsAt1kHz) {
  const std::string d = std::to_string(domains::kRoundTrip);
  const std::string master_json = tmp("master.json"), server_json = tmp("server.json");
  const std::string log = tmp("master.csv");
  Process server(
      kServerBinary,
      {"--domain", d, "--duration", "60", "--summary-json", server_json, "--scene", kToolScene},
      "rt_server");
  Process master(kMasterBinary,
                 {"--domain", d, "--samples", "4500", "--homing", "1", "--summary-json",
                  master_json, "--log", log, "--script", "press-slip"},
                 "rt_master");
  ASSERT_EQ(master.wait_for(60.0), 0) << master.err();
  server.signal(SIGTERM);
  ASSERT_EQ(server.wait_for(20.0), 0) << server.err();

  const std::string m = Process::slurp(master_json);
  const double sent = json_value(m, "sent");
  const double received = json_value(m, "received");
  // the 4500 cycles asked for, then the fade-out of the force at the rate bound (10 N at most,
  // 1 N per cycle) while the slave holds
  const double closing = json_value(m, "closing_cycles");
  EXPECT_GE(closing, 1.0) << m;
  EXPECT_LE(closing, 11.0) << m;
  EXPECT_EQ(sent, 4500 + closing) << m;
  EXPECT_GE(received, 0.99 * sent) << m;
  EXPECT_EQ(json_value(m, "lost"), sent - received) << m;
  // generous bound: a loaded 2-core CI machine, plus up to one physics period of waiting
  const double p99 = json_nested(m, "rtt_ms", "p99");
  EXPECT_GT(p99, 0.0) << m;
  EXPECT_LT(p99, 50.0) << m;
  // the server echoes the newest command once per step: not every command gets an echo
  EXPECT_GE(json_nested(m, "rtt_ms", "count"), 0.5 * sent) << m;
  EXPECT_FALSE(std::isnan(json_nested(m, "loop_jitter_us", "p50"))) << m;
  EXPECT_FALSE(std::isnan(json_nested(m, "loop_jitter_us", "p99"))) << m;

  const std::string s = Process::slurp(server_json);
  EXPECT_GE(json_value(s, "commands_received"), received) << s;
  EXPECT_EQ(json_value(s, "commands_rejected_nan"), 0) << s;
  EXPECT_EQ(json_value(s, "faults"), 0) << s;
  EXPECT_NE(master.out().find("session summary"), std::string::npos);
  // the CSV log has a header and one row per command
  const std::string csv = Process::slurp(log);
  EXPECT_EQ(static_cast<int>(std::count(csv.begin(), csv.end(), '\n')), 4501 + closing);
  // the press-slip script reaches the floor: the slave reported contact during the session
  const auto header_end = csv.find('\n');
  const std::string header = csv.substr(0, header_end);
  EXPECT_NE(header.find("in_contact"), std::string::npos) << header;
  const std::string m_all = Process::slurp(master_json);
  EXPECT_GT(json_nested(m_all, "metrics", "contact_time_s"), 0.1) << m_all;
}

TEST(Loopback, UnknownFlagsPrintUsageAndExit2) {
  Process s(kServerBinary, {"--no-such-flag"}, "flag_server");
  EXPECT_EQ(s.wait_for(10.0), 2);
  EXPECT_NE(s.err().find("Usage"), std::string::npos) << s.err();
  Process m(kMasterBinary, {"--samples", "ten"}, "flag_master");
  EXPECT_EQ(m.wait_for(10.0), 2);
  Process m2(kMasterBinary, {"--script", "teleport"}, "flag_master2");
  EXPECT_EQ(m2.wait_for(10.0), 2);
  Process m3(kMasterBinary, {"--rate", "0"}, "flag_master3");
  EXPECT_EQ(m3.wait_for(10.0), 2);
  EXPECT_NE(m3.err().find("--rate"), std::string::npos) << m3.err();
}

TEST(Loopback, BadSceneNamesFileFieldValueAndRangeAndExits2) {
  const std::string scene = tmp("bad_scene.yaml");
  std::ofstream(scene) << "name: bad\nphysics:\n  rate_hz: -5\n";
  Process s(kServerBinary, {"--scene", scene, "--domain", "200"}, "bad_scene");
  EXPECT_EQ(s.wait_for(10.0), 2);
  const std::string err = s.err();
  EXPECT_NE(err.find(scene), std::string::npos) << err;
  EXPECT_NE(err.find("physics.rate_hz"), std::string::npos) << err;
  EXPECT_NE(err.find("-5"), std::string::npos) << err;
  EXPECT_NE(err.find("[10, 20000]"), std::string::npos) << err;
}

TEST(Loopback, BadProfileOrDomainExits2) {
  Process s(kServerBinary, {"--profile", "no_such_profile"}, "bad_profile");
  EXPECT_EQ(s.wait_for(10.0), 2);
  EXPECT_NE(s.err().find("loopback"), std::string::npos) << s.err();  // lists what exists
  Process m(kMasterBinary, {"--domain", "999"}, "bad_domain");
  EXPECT_EQ(m.wait_for(10.0), 2);
  EXPECT_NE(m.err().find("[0, 232]"), std::string::npos) << m.err();
}

/// Publishes hand-made commands into a server, as a broken or hostile master would.
class CommandInjector {
 public:
  explicit CommandInjector(int domain)
      : participant_(dds::ParticipantOptions{"loopback", domain, "injector"}),
        writer_(participant_, dds::topics::kMasterCommand),
        reader_(participant_, dds::topics::kSlaveState,
                [this](const SlaveState& s, const eprosima::fastdds::dds::SampleInfo&) {
                  holding_ = s.holding();
                  ++states_;
                  last_x_ = s.tip_position_m()[0];
                }) {}

  bool wait_matched(double timeout_s) {
    const auto t0 = now_ns();
    while (seconds_between(t0, now_ns()) < timeout_s) {
      if (writer_.matched() > 0 && states_ > 0) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return false;
  }
  void send(MasterCommand c) {
    c.send_time_ns(now_ns());
    writer_.write(c);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  bool holding() const { return holding_; }
  double last_x() const { return last_x_; }

 private:
  dds::Participant participant_;
  dds::Writer<MasterCommandPubSubType> writer_;
  std::atomic<bool> holding_{false};
  std::atomic<int> states_{0};
  std::atomic<double> last_x_{0.0};
  dds::Reader<SlaveStatePubSubType> reader_;
};

/// Arguments of a tool-scene server on `domain` with a summary file and a watchdog timeout [s].
std::vector<std::string> tool_server_args(int domain, const std::string& summary_json,
                                          const std::string& command_timeout_s) {
  return {"--domain",   std::to_string(domain), "--duration",      "60",      "--summary-json",
          summary_json, "--command-timeout",    command_timeout_s, "--scene", kToolScene};
}

MasterCommand command(std::uint64_t seq, double x) {
  MasterCommand c;
  c.seq(seq);
  c.position_m() = {x, 0.0, 0.4};
  c.orientation_wxyz() = {1, 0, 0, 0};
  c.enabled(true);
  return c;
}

TEST(Loopback, InvalidCommandsAreRejectedCountedAndNeverReachThePhysics) {
  const int domain = domains::kBadCommands;
  const std::string server_json = tmp("bad_cmd_server.json");
  Process server(kServerBinary, tool_server_args(domain, server_json, "5"), "bad_cmd_server");
  CommandInjector inj(domain);
  ASSERT_TRUE(inj.wait_matched(20.0));
  std::uint64_t seq = 0;
  for (int i = 0; i < 20; ++i) inj.send(command(++seq, 0.5));  // valid, x = 0.5
  auto nan_cmd = command(++seq, std::nan(""));
  for (int i = 0; i < 5; ++i) {
    nan_cmd.seq(++seq);
    inj.send(nan_cmd);
  }
  auto inf_cmd = command(++seq, 0.5);
  inf_cmd.linear_velocity_mps()[1] = INFINITY;
  inj.send(inf_cmd);
  for (int i = 0; i < 4; ++i) inj.send(command(++seq, 50.0));  // far outside the workspace
  inj.send(command(3, 0.9));                                   // stale: old sequence number
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  // the tool tracked only the valid commands
  EXPECT_NEAR(inj.last_x(), 0.5, 0.02);
  server.signal(SIGTERM);
  ASSERT_EQ(server.wait_for(20.0), 0) << server.err();
  const std::string s = Process::slurp(server_json);
  EXPECT_EQ(json_value(s, "commands_rejected_nan"), 6) << s;
  EXPECT_EQ(json_value(s, "commands_rejected_workspace"), 4) << s;
  EXPECT_EQ(json_value(s, "commands_rejected_stale"), 1) << s;
  EXPECT_EQ(json_value(s, "commands_accepted"), 20) << s;
  EXPECT_EQ(json_value(s, "faults"), 0) << s;
}

TEST(Loopback, ServerHoldsTheSlaveWhenCommandsStop) {
  const int domain = domains::kWatchdog;
  const std::string server_json = tmp("wd_server.json");
  Process server(kServerBinary, tool_server_args(domain, server_json, "0.05"), "wd_server");
  CommandInjector inj(domain);
  ASSERT_TRUE(inj.wait_matched(20.0));
  std::uint64_t seq = 0;
  for (int i = 0; i < 100; ++i) inj.send(command(++seq, 0.5));
  EXPECT_FALSE(inj.holding());
  std::this_thread::sleep_for(std::chrono::milliseconds(400));  // silence > 50 ms
  EXPECT_TRUE(inj.holding());
  for (int i = 0; i < 50; ++i) inj.send(command(++seq, 0.5));  // commands resume
  EXPECT_FALSE(inj.holding());
  server.signal(SIGTERM);
  ASSERT_EQ(server.wait_for(20.0), 0);
  EXPECT_EQ(json_value(Process::slurp(server_json), "watchdog_trips"), 1);
}

TEST(Loopback, MasterFadesForceToZeroWhenTheServerDisappears) {
  const std::string d = std::to_string(domains::kLinkLoss);
  const std::string master_json = tmp("ll_master.json"), log = tmp("ll_master.csv");
  Process server(kServerBinary, {"--domain", d, "--duration", "60", "--scene", kToolScene},
                 "ll_server");
  Process master(kMasterBinary,
                 {"--domain", d, "--duration", "4", "--summary-json", master_json, "--log", log,
                  "--script", "press-slip", "--link-timeout", "0.05"},
                 "ll_master");
  std::this_thread::sleep_for(std::chrono::milliseconds(2500));
  server.signal(SIGKILL);  // abrupt loss, no goodbye
  // the commands of the last seconds never arrived: the session is degraded (exit status 5)
  ASSERT_EQ(master.wait_for(30.0), 5) << master.err();
  const std::string m = Process::slurp(master_json);
  EXPECT_GE(json_value(m, "link_losses"), 1) << m;
  EXPECT_EQ(json_text(m, "verdict"), "degraded") << m;
  EXPECT_NE(m.find("commands lost ("), std::string::npos) << m;
  // the last rows of the log: link down and zero rendered force
  const std::string csv = Process::slurp(log);
  const auto last_line_start = csv.rfind('\n', csv.size() - 2) + 1;
  const std::string last = csv.substr(last_line_start);
  // columns 12-14 are fm_x, fm_y, fm_z (the rendered force): all zero at the end
  std::vector<double> cols;
  for (std::size_t p = 0; p < last.size();) {
    cols.push_back(std::atof(last.c_str() + p));
    const auto comma = last.find(',', p);
    if (comma == std::string::npos) break;
    p = comma + 1;
  }
  ASSERT_GE(cols.size(), 15u) << last;
  EXPECT_EQ(cols[12], 0.0) << last;
  EXPECT_EQ(cols[13], 0.0) << last;
  EXPECT_EQ(cols[14], 0.0) << last;
  std::system("fastdds shm clean >/dev/null 2>&1");  // the killed server leaked SHM segments
}

}  // namespace
}  // namespace teleop::test

namespace teleop::test {
namespace {

/// Largest "<name> <rate> Hz" figure printed by teleop_monitor.
double max_rate(const std::string& out, const std::string& name) {
  double best = 0.0;
  std::size_t pos = 0;
  while ((pos = out.find(name, pos)) != std::string::npos) {
    pos += name.size();
    best = std::max(best, std::atof(out.c_str() + pos));
  }
  return best;
}

TEST(Loopback, ObserversJoinAndLeaveWithoutDisturbingTheLoop) {
  const std::string d = std::to_string(domains::kMonitor);
  const std::string master_json = tmp("obs_master.json");
  const std::string monitor = std::string(TELEOP_BINARY_DIR) + "/client/teleop_monitor";
  // server and master start together; observers join later and leave before the end
  Process server(kServerBinary, {"--domain", d, "--duration", "60", "--scene", kToolScene},
                 "obs_server");
  Process master(kMasterBinary, {"--domain", d, "--samples", "4000", "--summary-json", master_json},
                 "obs_master");
  std::this_thread::sleep_for(std::chrono::milliseconds(700));
  // full-rate observers (the 1 kHz topics), the heaviest kind; observers_test.cpp covers the
  // default, rate-limited ones
  Process mon1(monitor, {"--domain", d, "--duration", "2", "--period", "0.5", "--full-rate"},
               "obs_mon1");
  Process mon2(monitor, {"--domain", d, "--duration", "1.5", "--period", "0.5", "--full-rate"},
               "obs_mon2");
  ASSERT_EQ(mon1.wait_for(30.0), 0) << mon1.err();
  ASSERT_EQ(mon2.wait_for(30.0), 0) << mon2.err();
  ASSERT_EQ(master.wait_for(60.0), 0) << master.err();
  server.signal(SIGTERM);
  ASSERT_EQ(server.wait_for(20.0), 0);
  for (const Process* mon : {&mon1, &mon2}) {
    const std::string out = mon->out();
    EXPECT_GT(max_rate(out, "slave_state"), 500.0) << out;
    EXPECT_GT(max_rate(out, "master_state"), 50.0) << out;
    EXPECT_NE(out.find("scene 'tool-only'"), std::string::npos) << out;  // transient local
  }
  const std::string m = Process::slurp(master_json);
  EXPECT_GE(json_value(m, "received"), 0.99 * json_value(m, "sent")) << m;
}

}  // namespace
}  // namespace teleop::test
