// The passivity schemes end to end over loopback DDS: a real teleop_server on the tool-only
// scene and a real teleop_master with wave-variables or tdpa across an injected delay; and a
// hostile writer whose wave fields the server must reject. Each test has its own domain id.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "common/dds/endpoint.hpp"
#include "common/util/clock.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"
#include "tests/support/domains.hpp"
#include "tests/support/integration.hpp"
#include "tests/support/process.hpp"

namespace teleop::test {
namespace {

const std::string kToolScene = scene_file("tool_only.yaml");

std::string tmp(const std::string& name) { return temp_path("pv", name); }

void run_session(const std::string& scheme, int domain, const std::string& tag) {
  const std::string d = std::to_string(domain);
  const std::string mj = tmp(tag + "_master.json"), sj = tmp(tag + "_server.json");
  const std::string log = tmp(tag + "_master.csv");
  Process server(kServerBinary,
                 {"--domain", d, "--duration", "60", "--summary-json", sj, "--scene", kToolScene},
                 tag + "_server");
  Process master(
      kMasterBinary,
      {"--domain", d, "--scheme", scheme, "--delay", "50ms", "--jitter", "2ms", "--seed", "3",
       "--homing", "1", "--script", "press-slip", "--summary-json", mj, "--log", log},
      tag + "_master");
  ASSERT_EQ(master.wait_for(90.0), 0) << master.err();
  server.signal(SIGTERM);
  ASSERT_EQ(server.wait_for(20.0), 0) << server.err();

  const std::string m = Process::slurp(mj);
  EXPECT_NE(m.find("\"scheme\": \"" + scheme + "\""), std::string::npos) << m;
  // stable, no safety cut, passive at the operator's port
  EXPECT_EQ(json_text(m, "verdict"), "stable") << m;
  EXPECT_NE(m.find("\"cut\": false"), std::string::npos) << m;
  EXPECT_GE(json_nested(m, "metrics", "energy_min_j"), -1e-3) << m;
  // the tool went down to the floor and pressed it, and followed the master
  EXPECT_GT(json_nested(m, "metrics", "contact_time_s"), 0.5) << m;
  EXPECT_LT(json_nested(m, "metrics", "position_error_rms_m"), 0.02) << m;
  EXPECT_LE(json_nested(m, "metrics", "max_device_force_n"), 10.0 + 1e-9) << m;

  const std::string s = Process::slurp(sj);
  EXPECT_EQ(json_value(s, "commands_rejected_nan"), 0) << s;
  EXPECT_EQ(json_value(s, "commands_rejected_passivity"), 0) << s;
  EXPECT_EQ(json_value(s, "faults"), 0) << s;

  // per-cycle log: the slave is back with the master at the end (script over, hand still),
  // and the master-side passivity observer never went negative
  const auto cols =
      csv_columns(Process::slurp(log), {"phase", "position_error_m", "passivity_observer_j"});
  ASSERT_GT(cols[0].size(), 3000u);
  double observer_min = 0.0;
  for (std::size_t i = 0; i < cols[0].size(); ++i) {
    if (cols[0][i] == 1.0) observer_min = std::min(observer_min, cols[2][i]);
  }
  EXPECT_GE(observer_min, -1e-6);
  EXPECT_LT(cols[1].back(), 3e-3) << "final position error";
}

TEST(Passivity, WaveVariablesSessionOverDdsFollowsAndIsStable) {
  run_session("wave-variables", domains::kWaveSession, "wave");
}

TEST(Passivity, TdpaSessionOverDdsFollowsAndIsStable) {
  run_session("tdpa", domains::kTdpaSession, "tdpa");
}

/// A usable wave-variables command of session 42 (tool at (0.6, 0, 0.7)): impedance `b`
/// [N s/m], the integral [sqrt(W) s] and the energy [J] of the wave sent so far along z.
MasterCommand wave_command(std::uint64_t seq, double b, double integral, double energy) {
  MasterCommand c;
  c.seq(seq);
  c.position_m() = {0.6, 0.0, 0.7};
  c.orientation_wxyz() = {1, 0, 0, 0};
  c.enabled(true);
  c.scheme(SCHEME_WAVE_VARIABLES);
  c.passivity_session(42);
  c.wave_impedance_ns_per_m(b);
  c.wave_u_integral() = {0.0, 0.0, integral};
  c.wave_u_energy_j() = {0.0, 0.0, energy};
  return c;
}

TEST(Passivity, ServerRejectsUnusableWaveCommandsAndCountsThem) {
  const int domain = domains::kBadWaveCommands;
  const std::string sj = tmp("badwave_server.json");
  Process server(kServerBinary,
                 {"--domain", std::to_string(domain), "--duration", "60", "--summary-json", sj,
                  "--command-timeout", "5", "--scene", kToolScene},
                 "badwave_server");
  dds::Participant participant(dds::ParticipantOptions{"loopback", domain, "wave_injector"});
  dds::Writer<MasterCommandPubSubType> writer(participant, dds::topics::kMasterCommand);
  std::atomic<int> states{0};
  std::atomic<double> last_z{0.0};
  std::atomic<bool> finite{true};
  dds::Reader<SlaveStatePubSubType> reader(
      participant, dds::topics::kSlaveState,
      [&](const SlaveState& s, const eprosima::fastdds::dds::SampleInfo&) {
        ++states;
        last_z = s.tip_position_m()[2];
        for (double v : s.tip_position_m()) finite = finite && std::isfinite(v);
        for (double v : s.wave_v_integral()) finite = finite && std::isfinite(v);
      });
  const auto t0 = now_ns();
  while ((writer.matched() == 0 || states == 0) && seconds_between(t0, now_ns()) < 20.0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_GT(writer.matched(), 0);
  std::uint64_t seq = 0;
  double integral = 0.0, energy = 0.0;
  const double b = 10.0, u = -std::sqrt(2.0 * b) * 0.05;  // down at 5 cm/s
  const auto send = [&](MasterCommand c) {
    c.send_time_ns(now_ns());
    writer.write(c);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  };
  const auto good = [&]() { return wave_command(++seq, b, integral, energy); };
  for (int i = 0; i < 100; ++i) {  // 0.2 s at 2 ms: about 1 cm down
    integral += 0.002 * u;
    energy += 0.5 * 0.002 * u * u;
    send(good());
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const double z_good = last_z;
  EXPECT_LT(z_good, 0.7 - 0.003);  // the wave moved the tool down
  auto nan = good();
  nan.wave_u_integral()[2] = std::nan("");
  send(nan);
  auto bad_b = good();
  bad_b.wave_impedance_ns_per_m(-1.0);
  send(bad_b);
  auto negative = good();
  negative.wave_u_energy_j()[2] = -1.0;
  send(negative);
  auto stale = good();
  stale.wave_u_energy_j()[2] = 0.5 * energy;  // older energy within the session
  send(stale);
  auto huge = good();
  huge.wave_u_integral()[2] = -1e6;  // finite and within range: bounded by its energy
  send(huge);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  EXPECT_TRUE(finite);
  // the wave with no energy behind it moved the tool by no more than the energy allowed
  EXPECT_GT(last_z, z_good - 0.01);
  server.signal(SIGTERM);
  ASSERT_EQ(server.wait_for(20.0), 0) << server.err();
  const std::string s = Process::slurp(sj);
  EXPECT_EQ(json_value(s, "commands_rejected_nan"), 1) << s;
  EXPECT_EQ(json_value(s, "commands_rejected_passivity"), 3) << s;
  EXPECT_EQ(json_value(s, "faults"), 0) << s;
}

}  // namespace
}  // namespace teleop::test
