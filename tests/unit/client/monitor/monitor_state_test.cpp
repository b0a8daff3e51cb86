// teleop_monitor's renderings of the experiment (teleop/experiment): the line log, the screen
// and the JSON show the scheme, the gains, the injected delay, jitter and loss, the loop delay
// the controller lives with and the device; before a master described its session they say so.
#include "client/monitor/monitor_state.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <nlohmann/json.hpp>
#include <string>

namespace teleop::monitor {
namespace {

ExperimentDescription experiment_50ms_2pct() {
  ExperimentDescription e;
  e.master_session(0x1234u);
  e.scheme("force-position");
  e.master_stiffness_n_per_m(2000.0);
  e.master_damping_ns_per_m(2.0);
  e.force_gain(1.0);
  e.slave_stiffness_n_per_m(1500.0);
  e.forward_delay_ms(50.0);
  e.backward_delay_ms(50.0);
  e.forward_jitter_ms(5.0);
  e.backward_jitter_ms(5.0);
  e.forward_jitter_dist("normal");
  e.backward_jitter_dist("normal");
  e.forward_loss(0.02);
  e.backward_loss(0.02);
  e.forward_seed(7);
  e.backward_seed(8);
  e.loop_delay_p50_ms(101.25);
  e.loop_delay_p99_ms(112.5);
  e.loop_delay_count(950);
  e.device("external");
  e.device_kind(DEVICE_EXTERNAL);
  e.driver_live(true);
  e.driver_timeout_ms(100.0);
  return e;
}

Snapshot live_session() {
  Snapshot s;
  s.t_s = 12.0;
  s.domain = 7;
  s.profile = "loopback";
  s.topics = {{"slave_state", false, 0.5, 100, 10.0, 0.01},
              {"master_state", false, 0.5, 100, 10.0, 0.01}};
  s.have_slave = s.have_master = true;
  s.master.rtt_ms(0.652);
  s.master.link_ok(true);
  return s;
}

TEST(MonitorExperiment, TheLineShowsSchemeDelayJitterLossAndLoopDelay) {
  Snapshot s = live_session();
  s.have_experiment = true;
  s.experiment = experiment_50ms_2pct();
  const std::string lines = render_lines(s);
  SCOPED_TRACE(lines);
  // the network's round trip stays on the master line; the experiment line says what it sits on
  EXPECT_NE(lines.find("rtt 0.652 ms"), std::string::npos);
  EXPECT_NE(lines.find("experiment force-position"), std::string::npos);
  EXPECT_NE(lines.find("K_pm 2000 N/m"), std::string::npos);
  EXPECT_NE(lines.find("K_ps 1500 N/m"), std::string::npos);
  EXPECT_NE(lines.find("delay 50 ms"), std::string::npos);
  EXPECT_NE(lines.find("jitter 5 ms normal"), std::string::npos);
  EXPECT_NE(lines.find("loss 2 %"), std::string::npos);
  EXPECT_NE(lines.find("burst off"), std::string::npos);
  EXPECT_NE(lines.find("seed 7/8"), std::string::npos);
  EXPECT_NE(lines.find("loop delay p50 101.2 ms p99 112.5 ms"), std::string::npos);
  EXPECT_NE(lines.find("device external live"), std::string::npos);
}

TEST(MonitorExperiment, DirectionsThatDifferAndASilentDeviceAreShown) {
  Snapshot s = live_session();
  s.have_experiment = true;
  s.experiment = experiment_50ms_2pct();
  s.experiment.backward_delay_ms(10.0);
  s.experiment.backward_loss(0.0);
  s.experiment.forward_burst_p_gb(0.01);
  s.experiment.forward_burst_p_bg(0.3);
  s.experiment.driver_live(false);
  s.experiment.driver_silences(2);
  s.experiment.driver_silent_s(3.5);
  s.experiment.loop_delay_p50_ms(std::numeric_limits<double>::quiet_NaN());
  const std::string line = experiment_line(s);
  SCOPED_TRACE(line);
  EXPECT_NE(line.find("delay 50/10 ms"), std::string::npos);
  EXPECT_NE(line.find("loss 2/0 %"), std::string::npos);
  EXPECT_NE(line.find("burst 0.01/0,0.3/0"), std::string::npos);
  EXPECT_NE(line.find("loop delay p50 n/a ms"), std::string::npos);
  EXPECT_NE(line.find("SILENT"), std::string::npos);
  EXPECT_NE(line.find("silent 2 times, 3.50 s"), std::string::npos);
}

TEST(MonitorStatus, AnInsecureProfileIsShownOnScreenAndInJson) {
  Snapshot s = live_session();
  EXPECT_NE(render_json(s).find("\"insecure\": false"), std::string::npos);
  EXPECT_EQ(render_screen(s, 40, 0)[0].find("INSECURE"), std::string::npos);
  s.insecure = true;
  EXPECT_NE(render_json(s).find("\"insecure\": true"), std::string::npos);
  EXPECT_NE(render_screen(s, 40, 0)[0].find("INSECURE (no DDS Security)"), std::string::npos)
      << render_screen(s, 40, 0)[0];
}

TEST(MonitorExperiment, ScreenAndJsonCarryItAndSayWhenThereIsNone) {
  Snapshot s = live_session();
  const std::vector<std::string> before = render_screen(s, 40, 0);
  bool none = false;
  for (const auto& l : before) none = none || l.find("experiment (none yet") == 0;
  EXPECT_TRUE(none);
  EXPECT_NE(render_json(s).find("\"experiment\": null"), std::string::npos);
  EXPECT_EQ(render_lines(s).find("experiment"), std::string::npos);

  s.have_experiment = true;
  s.experiment = experiment_50ms_2pct();
  bool shown = false;
  for (const auto& l : render_screen(s, 40, 0)) {
    shown = shown || l.find("experiment force-position") == 0;
  }
  EXPECT_TRUE(shown);
  const std::string json = render_json(s);
  EXPECT_NE(json.find("\"scheme\": \"force-position\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"forward_delay_ms\": 50"), std::string::npos) << json;
  EXPECT_NE(json.find("\"forward_loss\": 0.02"), std::string::npos) << json;
  EXPECT_NE(json.find("\"loop_delay_p99_ms\": 112.5"), std::string::npos) << json;
  EXPECT_NE(json.find("\"forward_jitter_dist\": \"normal\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"seeds\": [7, 8]"), std::string::npos) << json;
  // the description is latched: once its master is gone the line says so
  s.topics[1].age_s = 2.0;
  EXPECT_EQ(experiment_line(s).find("experiment (master gone"), 0u) << experiment_line(s);
}

TEST(MonitorJson, EveryLineParsesAndTextComesBackUnchanged) {
  EventView e;
  e.at_s = 1.5;
  e.event.source("server");
  e.event.message("a \"quoted\" \\ line\nbreak\x01 and a bad byte \xff");
  e.event.value(std::numeric_limits<double>::quiet_NaN());
  const auto ev = nlohmann::ordered_json::parse(event_json(e));
  EXPECT_EQ(ev["type"], "event");
  EXPECT_EQ(ev["source"], "server");
  EXPECT_EQ(ev["message"], "a \"quoted\" \\ line\nbreak\x01 and a bad byte \xEF\xBF\xBD");
  EXPECT_TRUE(ev["value"].is_null()) << "NaN is written as null";
  EXPECT_EQ(ev.begin().key(), "type") << "keys stay in the order written";

  Snapshot s = live_session();
  s.profile = "lo\"op";
  s.have_experiment = true;
  s.experiment = experiment_50ms_2pct();
  const auto st = nlohmann::ordered_json::parse(render_json(s));
  EXPECT_EQ(st["type"], "status");
  EXPECT_EQ(st["profile"], "lo\"op");
  EXPECT_EQ(st["experiment"]["scheme"], "force-position");
  EXPECT_EQ(st["experiment"]["seeds"], nlohmann::ordered_json::array({7, 8}));
  EXPECT_EQ(nlohmann::ordered_json::parse(experiment_json(s.experiment)), st["experiment"]);
}

}  // namespace
}  // namespace teleop::monitor
