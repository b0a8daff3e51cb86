// A device driver that goes silent (teleop_viewer --drive that quits, a hardware driver that
// hangs): an external driver process writes teleop/device_state, presses the slave into the
// floor of the tool-only scene, then stops writing mid-session. The master must hold the slave
// where it is, fade the force to zero at the device's rate bound (no step above it), say so
// (an event, the summary's device line) and leave the silent time out of the figures; the
// session is judged "degraded" (docs/exit_codes.md) unless the loop's own verdict is worse.
// An observer that joins after the silence began reads teleop/experiment from the latched
// history: the scheme, the injected delay, jitter and loss, the loop delay and the silence.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "common/dds/endpoint.hpp"
#include "common/util/clock.hpp"
#include "teleop/idl/DevicePubSubTypes.h"
#include "teleop/idl/TeleopPubSubTypes.h"
#include "tests/support/domains.hpp"
#include "tests/support/integration.hpp"
#include "tests/support/process.hpp"

namespace teleop::test {
namespace {

/// Everything teleop/experiment delivered to one reader.
struct ExperimentWatch {
  std::mutex m;
  std::vector<ExperimentDescription> samples;
  std::atomic<std::int64_t> last_rx_ns{0};
  std::atomic<std::int64_t> first_time_ns{0};  // the first sample's time_ns (master clock)
  void add(const ExperimentDescription& e) {
    std::lock_guard<std::mutex> l(m);
    samples.push_back(e);
    if (samples.size() == 1) first_time_ns = e.time_ns();
    last_rx_ns = now_ns();
  }
  std::size_t count() {
    std::lock_guard<std::mutex> l(m);
    return samples.size();
  }
};

/// The driver: 5 cm above the contact point, then 2 mm below it; it falls silent once the
/// master has run 3 s with it (the session lasts 5 s after homing).
void drive_then_fall_silent(dds::Writer<DeviceStatePubSubType>& states, ExperimentWatch& early,
                            const std::atomic<bool>& stop, std::atomic<std::uint64_t>& written) {
  DeviceState s;
  const auto t0 = now_ns();
  while (!stop) {
    const double t = seconds_between(t0, now_ns());
    const double z = t < 1.0 ? 0.05 : std::max(-0.002, 0.05 - 0.1 * (t - 1.0));
    s.seq(written + 1);
    s.time_ns(now_ns());
    s.position_m() = {0.0, 0.0, z};
    s.orientation_wxyz() = {1, 0, 0, 0};
    s.engaged(true);
    s.max_force_n(10.0);
    states.write(s);
    ++written;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    // silent from the third second of the session on (the master waits for the server and
    // homes first: count from its first description)
    if (early.first_time_ns != 0 && seconds_between(early.first_time_ns, now_ns()) > 3.0) {
      break;
    }
  }
}

/// Waits (at most 3 s) until a periodic description has just arrived, at least 0.5 s on.
void wait_just_after_a_description(const ExperimentWatch& early) {
  const auto wait0 = now_ns();
  while (seconds_between(wait0, now_ns()) < 3.0 &&
         (early.last_rx_ns == 0 || seconds_between(early.last_rx_ns, now_ns()) > 0.05 ||
          seconds_between(wait0, now_ns()) < 0.5)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
}

/// The master's summary `m`, exit status `rc` and output report the silence.
void expect_silence_reported(const std::string& m, int rc, Process& master) {
  // the verdict: degraded by the silence, or the loop's own when worse; the exit status is its
  // verdict's (docs/exit_codes.md)
  ASSERT_EQ(rc, verdict_exit_status(m));
  EXPECT_GE(rc, 5);
  EXPECT_NE(m.find("the device fell silent"), std::string::npos);
  // the silence, reported with its length (at least one: a loaded machine may starve the fake
  // driver past the timeout before it stops for good); the figures cover the live time only
  EXPECT_GE(json_nested(m, "driver", "silences"), 1.0);
  EXPECT_GT(json_nested(m, "driver", "silent_s"), 0.5);
  EXPECT_LT(json_nested(m, "driver", "live_s"), json_value(m, "session_s"));
  EXPECT_NE(master.err().find("device silent"), std::string::npos);
  EXPECT_NE(master.out().find("device          live"), std::string::npos) << master.out();
  EXPECT_NE(master.out().find("the device was live"), std::string::npos);
  // no force step above the device's rate bound (1000 N/s: 1 N per 1 ms cycle), ever
  EXPECT_LE(json_nested(m, "safety", "max_step_n"), 1.0 + 1e-9);
}

/// The master's log: after the silence began the force went to zero in steps within the
/// bound, and the slave held where it was.
void expect_force_faded_and_slave_held(const std::string& log) {
  const auto cols = csv_columns(Process::slurp(log),
                                {"t_s", "phase", "fm_x", "fm_y", "fm_z", "xs_x", "xs_y", "xs_z"});
  ASSERT_GT(cols[0].size(), 1000u);
  // the driver's final silence: the last live cycle (phase 1) is followed by held ones to the end
  std::size_t silent = cols[1].size();
  while (silent > 0 && cols[1][silent - 1] == 0.0) --silent;
  ASSERT_GT(silent, 0u) << "no live cycle in the log";
  ASSERT_LT(silent + 500, cols[1].size()) << "no silence in the log";
  auto force = [&](std::size_t i) {
    return std::sqrt(cols[2][i] * cols[2][i] + cols[3][i] * cols[3][i] + cols[4][i] * cols[4][i]);
  };
  double max_step = 0.0;
  for (std::size_t i = silent; i + 1 < cols[0].size(); ++i) {
    max_step = std::max(max_step, std::abs(force(i + 1) - force(i)));
  }
  EXPECT_LE(max_step, 1.0 + 1e-6);
  EXPECT_EQ(force(silent + 400), 0.0);  // at most 10 N at 1 N per cycle: zero after 10 cycles
  const std::size_t end = cols[0].size() - 1;
  const double moved = std::sqrt(std::pow(cols[5][end] - cols[5][silent + 300], 2) +
                                 std::pow(cols[6][end] - cols[6][silent + 300], 2) +
                                 std::pow(cols[7][end] - cols[7][silent + 300], 2));
  EXPECT_LT(moved, 0.005);
}

/// The late observer got the description from the history, written before it joined.
void expect_late_observer_saw_experiment(ExperimentWatch& late, std::int64_t joined_ns) {
  std::lock_guard<std::mutex> l(late.m);
  ASSERT_FALSE(late.samples.empty());
  const ExperimentDescription& e = late.samples.front();
  EXPECT_LT(e.time_ns(), joined_ns);
  EXPECT_EQ(std::string(e.scheme().c_str()), "force-position");
  EXPECT_EQ(std::string(e.device().c_str()), "external");
  EXPECT_EQ(e.device_kind(), DEVICE_EXTERNAL);
  EXPECT_NEAR(e.forward_delay_ms(), 20.0, 1e-9);
  EXPECT_NEAR(e.backward_delay_ms(), 20.0, 1e-9);
  EXPECT_NEAR(e.forward_jitter_ms(), 2.0, 1e-9);
  EXPECT_NEAR(e.forward_loss(), 0.01, 1e-12);
  EXPECT_FALSE(e.driver_live());
  EXPECT_GE(e.driver_silences(), 1u);
  EXPECT_NEAR(e.driver_timeout_ms(), 100.0, 1e-9);
  // the loop delay the controller lives with: both injected delays and more
  EXPECT_GT(e.loop_delay_p50_ms(), 35.0);
  EXPECT_GT(e.master_stiffness_n_per_m(), 0.0);
}

TEST(DriverSilence, TheMasterHoldsFadesTheForceReportsItAndObserversSeeTheExperiment) {
  const int domain = domains::kDriverSilence;
  const std::string d = std::to_string(domain);
  const std::string mj = temp_path("driver_silence", "master.json");
  const std::string log = temp_path("driver_silence", "master.csv");
  Process server(
      kServerBinary,
      {"--domain", d, "--duration", "120", "--quiet", "--scene", scene_file("tool_only.yaml")},
      "silence_server");
  dds::Participant p(dds::ParticipantOptions{"loopback", domain, "silent-driver"});
  dds::Writer<DeviceStatePubSubType> states(p, dds::topics::kDeviceState);
  ExperimentWatch early, late;
  dds::Reader<ExperimentDescriptionPubSubType> early_reader(
      p, dds::topics::kExperiment,
      [&](const ExperimentDescription& e, const eprosima::fastdds::dds::SampleInfo&) {
        early.add(e);
      });
  std::atomic<bool> stop{false};
  std::atomic<std::uint64_t> written{0};
  Process master(kMasterBinary,
                 {"--domain", d,     "--device",         "external", "--duration",     "5",
                  "--homing", "0.5", "--delay",          "20ms",     "--jitter",       "2ms",
                  "--loss",   "1%",  "--driver-timeout", "100ms",    "--summary-json", mj,
                  "--log",    log},
                 "silence_master");
  std::thread driver([&] { drive_then_fall_silent(states, early, stop, written); });
  driver.join();
  // a late observer: joins after the silence began, right after a periodic description, so the
  // first sample it gets can only be the master's history (latched), written before it existed
  wait_just_after_a_description(early);
  dds::Participant lp(dds::ParticipantOptions{"loopback", domain, "late-observer"});
  const std::int64_t joined_ns = now_ns();
  dds::Reader<ExperimentDescriptionPubSubType> late_reader(
      lp, dds::topics::kExperiment,
      [&](const ExperimentDescription& e, const eprosima::fastdds::dds::SampleInfo&) {
        late.add(e);
      });
  const int rc = master.wait_for(60.0);
  stop = true;
  server.signal(SIGTERM);
  ASSERT_EQ(server.wait_for(30.0), 0);
  const std::string m = Process::slurp(mj);
  SCOPED_TRACE(m);
  SCOPED_TRACE(master.err());

  ASSERT_NO_FATAL_FAILURE(expect_silence_reported(m, rc, master));
  ASSERT_NO_FATAL_FAILURE(expect_force_faded_and_slave_held(log));
  expect_late_observer_saw_experiment(late, joined_ns);
}

}  // namespace
}  // namespace teleop::test
