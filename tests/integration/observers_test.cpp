// Observers on their defaults read the rate-limited topics (docs/topics.md, "Observer topics"):
// teleop_monitor gets the 10 Hz copies, a view-like subscriber the 60 Hz ones, a late observer
// gets the scene and the newest state at once, and a session with eight observer processes
// keeps its commands and its verdict. Rates are checked with generous bounds; what observers
// cost the loop is measured by `teleop_bench observers` (docs/results.md).
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <memory>
#include <sstream>
#include <thread>
#include <vector>

#include "common/dds/endpoint.hpp"
#include "common/dds/observer_topics.hpp"
#include "common/util/clock.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"
#include "tests/support/domains.hpp"
#include "tests/support/integration.hpp"
#include "tests/support/process.hpp"

namespace teleop::test {
namespace {

const std::string kMonitorBinary = std::string(TELEOP_BINARY_DIR) + "/client/teleop_monitor";
const std::string kToolScene = scene_file("tool_only.yaml");

std::string tmp(const std::string& name) { return temp_path("obs", name); }

/// The JSON status lines of a `teleop_monitor --json` output.
std::vector<std::string> status_lines(const std::string& out) {
  std::vector<std::string> lines;
  std::istringstream in(out);
  std::string line;
  while (std::getline(in, line)) {
    if (line.find("\"type\": \"status\"") != std::string::npos) lines.push_back(line);
  }
  return lines;
}

/// rate_hz of a topic in one status line.
double topic_rate(const std::string& line, const std::string& topic) {
  return json_nested(line, topic, "rate_hz");
}

/// The largest rate of `topic` over the status lines (the rate is over the last second).
double max_topic_rate(const std::vector<std::string>& lines, const std::string& topic) {
  double best = 0.0;
  for (const auto& l : lines) {
    const double r = topic_rate(l, topic);
    if (std::isfinite(r)) best = std::max(best, r);
  }
  return best;
}

/// An in-process observer that reads what teleop_viewer reads by default.
class ViewProbe {
 public:
  explicit ViewProbe(int domain)
      : topics_(dds::observer_topics(dds::ObserverKind::kView, false)),
        participant_(dds::ParticipantOptions{"loopback", domain, "view-probe"}),
        scene_(participant_, dds::topics::kScene,
               [this](const SceneDescription&, const Info&) { mark(scene_ns_); }),
        slave_(participant_, topics_.slave_state,
               [this](const SlaveState&, const Info&) {
                 mark(slave_ns_);
                 slave_count_.fetch_add(1);
               }),
        master_(participant_, topics_.master_state, [this](const MasterState&, const Info&) {
          mark(master_ns_);
          master_count_.fetch_add(1);
        }) {}

  using Info = eprosima::fastdds::dds::SampleInfo;
  std::int64_t created_ns() const { return created_ns_; }
  std::int64_t scene_ns() const { return scene_ns_.load(); }
  std::int64_t slave_ns() const { return slave_ns_.load(); }
  std::int64_t master_ns() const { return master_ns_.load(); }
  std::uint64_t slave_count() const { return slave_count_.load(); }
  std::uint64_t master_count() const { return master_count_.load(); }

 private:
  static void mark(std::atomic<std::int64_t>& first) {
    std::int64_t zero = 0;
    first.compare_exchange_strong(zero, now_ns());
  }
  std::int64_t created_ns_ = now_ns();
  dds::ObserverTopics topics_;
  dds::Participant participant_;
  std::atomic<std::int64_t> scene_ns_{0}, slave_ns_{0}, master_ns_{0};
  std::atomic<std::uint64_t> slave_count_{0}, master_count_{0};
  dds::Reader<SceneDescriptionPubSubType> scene_;
  dds::Reader<SlaveStatePubSubType> slave_;
  dds::Reader<MasterStatePubSubType> master_;
};

TEST(Observers, MonitorReadsTheTenHertzTopicsByDefault) {
  const std::string d = std::to_string(domains::kObserverRates);
  const std::string master_json = tmp("rates_master.json");
  Process server(kServerBinary, {"--domain", d, "--duration", "40", "--scene", kToolScene},
                 "obs_rates_server");
  Process master(kMasterBinary,
                 {"--domain", d, "--duration", "6", "--homing", "0.5", "--summary-json",
                  master_json, "--quiet"},
                 "obs_rates_master");
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  // two default monitors and one with --full-rate, for contrast
  Process mon1(kMonitorBinary, {"--domain", d, "--json", "--duration", "4", "--period", "0.5"},
               "obs_rates_mon1");
  Process mon2(kMonitorBinary, {"--domain", d, "--json", "--duration", "4", "--period", "0.5"},
               "obs_rates_mon2");
  ViewProbe view(domains::kObserverRates);
  std::this_thread::sleep_for(std::chrono::milliseconds(1000));
  const std::uint64_t view_slave_0 = view.slave_count();
  const auto t_view_0 = now_ns();
  std::this_thread::sleep_for(std::chrono::milliseconds(2000));
  const double view_slave_hz =
      static_cast<double>(view.slave_count() - view_slave_0) / seconds_between(t_view_0, now_ns());
  ASSERT_EQ(mon1.wait_for(30.0), 0) << mon1.err();
  ASSERT_EQ(mon2.wait_for(30.0), 0) << mon2.err();
  Process full(kMonitorBinary,
               {"--domain", d, "--json", "--duration", "2", "--period", "0.5", "--full-rate"},
               "obs_rates_full");
  ASSERT_EQ(full.wait_for(30.0), 0) << full.err();
  ASSERT_EQ(master.wait_for(60.0), 0) << master.err();
  server.signal(SIGTERM);
  ASSERT_EQ(server.wait_for(20.0), 0) << server.err();

  for (const Process* mon : {&mon1, &mon2}) {
    const std::string out = mon->out();
    const auto lines = status_lines(out);
    ASSERT_GE(lines.size(), 4u) << out;
    EXPECT_NE(lines.back().find("\"full_rate\": false"), std::string::npos) << lines.back();
    // advertised 10 Hz; generous bounds (a loaded machine, a one-second window)
    const double slave_hz = max_topic_rate(lines, "slave_state");
    EXPECT_GT(slave_hz, 4.0) << out;
    EXPECT_LT(slave_hz, 25.0) << out;  // far from the 1 kHz topic
    const double master_hz = max_topic_rate(lines, "master_state");
    EXPECT_GT(master_hz, 4.0) << out;
    EXPECT_LT(master_hz, 25.0) << out;
    // the command rate is the server's count: about 1 kHz while the master runs
    EXPECT_GT(max_topic_rate(lines, "master_command"), 300.0) << out;
    // only the master reads the full-rate SlaveState: the monitors are not among its readers
    EXPECT_EQ(json_nested(lines.back(), "server", "matched_state_readers"), 1.0) << lines.back();
    EXPECT_NE(out.find("\"type\": \"scene\""), std::string::npos) << out;
  }
  // the view copies: advertised 60 Hz
  EXPECT_GT(view_slave_hz, 25.0);
  EXPECT_LT(view_slave_hz, 120.0);
  EXPECT_GT(view.master_count(), 0u);
  // --full-rate: the 1 kHz topic and the master's own command topic
  const auto full_lines = status_lines(full.out());
  ASSERT_FALSE(full_lines.empty()) << full.out();
  EXPECT_NE(full_lines.back().find("\"full_rate\": true"), std::string::npos);
  EXPECT_GT(max_topic_rate(full_lines, "slave_state"), 300.0) << full.out();
  // (commands and verdict under observers: EightObserverProcessesKeepCommandsAndVerdict)
  const std::string m = Process::slurp(master_json);
  EXPECT_GT(json_value(m, "received"), 0.0) << m;
}

TEST(Observers, LateObserverGetsSceneAndNewestStateAtOnce) {
  const int domain = domains::kObserverLate;
  const std::string d = std::to_string(domain);
  Process server(kServerBinary, {"--domain", d, "--duration", "30", "--scene", kToolScene},
                 "obs_late_server");
  Process master(kMasterBinary, {"--domain", d, "--duration", "8", "--homing", "0.5", "--quiet"},
                 "obs_late_master");
  std::this_thread::sleep_for(std::chrono::milliseconds(2500));  // the session is running
  ViewProbe late(domain);
  const auto t0 = late.created_ns();
  while (seconds_between(t0, now_ns()) < 10.0 &&
         (late.scene_ns() == 0 || late.slave_ns() == 0 || late.master_ns() == 0)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_NE(late.scene_ns(), 0) << "no scene";
  ASSERT_NE(late.slave_ns(), 0) << "no slave state";
  ASSERT_NE(late.master_ns(), 0) << "no master state";
  // discovery on loopback (0.5 s announcements) plus the transient-local history: the scene
  // and the newest state arrive together, well before a slow period would bring them
  const double scene_s = seconds_between(t0, late.scene_ns());
  const double state_s = seconds_between(t0, late.slave_ns());
  std::printf(
      "late observer: scene after %.3f s, slave_state_view after %.3f s, "
      "master_state_view after %.3f s\n",
      scene_s, state_s, seconds_between(t0, late.master_ns()));
  EXPECT_LT(scene_s, 3.0);
  EXPECT_LT(state_s, 3.0);
  master.signal(SIGTERM);
  master.wait_for(20.0);
  server.signal(SIGTERM);
  ASSERT_EQ(server.wait_for(20.0), 0) << server.err();
}

TEST(Observers, EightObserverProcessesKeepCommandsAndVerdict) {
  const std::string d = std::to_string(domains::kObserverSession);
  const std::string master_json = tmp("eight_master.json"), server_json = tmp("eight_server.json");
  // the default scene: the sphere's mesh frames go to the observers too
  Process server(kServerBinary, {"--domain", d, "--duration", "50", "--summary-json", server_json},
                 "obs_eight_server");
  std::vector<std::unique_ptr<Process>> observers;
  for (int i = 0; i < 8; ++i) {
    std::vector<std::string> a = {"--domain", d, "--duration", "12"};
    if (i % 2 == 0) {
      a.push_back("--json");
    } else {
      a.push_back("--lines");
    }
    observers.push_back(
        std::make_unique<Process>(kMonitorBinary, a, "obs_eight_mon" + std::to_string(i)));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(2000));
  Process master(kMasterBinary,
                 {"--domain", d, "--duration", "5", "--summary-json", master_json, "--quiet"},
                 "obs_eight_master");
  ASSERT_EQ(master.wait_for(60.0), 0) << master.err();
  int with_scene = 0;
  for (auto& o : observers) {
    EXPECT_EQ(o->wait_for(30.0), 0) << o->err();
    const std::string out = o->out();
    if (out.find("scene 'default'") != std::string::npos ||
        out.find("\"type\": \"scene\"") != std::string::npos) {
      ++with_scene;
    }
  }
  server.signal(SIGTERM);
  ASSERT_EQ(server.wait_for(20.0), 0) << server.err();
  EXPECT_EQ(with_scene, 8);
  const std::string m = Process::slurp(master_json);
  std::printf(
      "8 observers: sent %.0f received %.0f, rtt p50 %.3f p99 %.3f ms, overruns %.0f, "
      "link losses %.0f\n",
      json_value(m, "sent"), json_value(m, "received"), json_nested(m, "rtt_ms", "p50"),
      json_nested(m, "rtt_ms", "p99"), json_value(m, "overruns"), json_value(m, "link_losses"));
  EXPECT_GE(json_value(m, "received"), 0.99 * json_value(m, "sent")) << m;
  EXPECT_EQ(json_text(m, "verdict"), "stable") << m;
  EXPECT_EQ(json_value(m, "link_losses"), 0.0) << m;
}

}  // namespace
}  // namespace teleop::test
