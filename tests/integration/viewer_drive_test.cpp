// Driving a session by hand and tuning it live: teleop_viewer --drive under Xvfb is the
// master's device (teleop_master --device external) and its tuning tool (--accept-tuning); a
// scripted input presses the slave into the elastic sphere with the keys, drags it sideways with
// the "mouse" (the viewer's own drag handler, fed pixel positions) and sends one good and two bad
// tuning requests. The test checks what each side measured, and what the slave did from the
// topics. A second test checks that a master started without --accept-tuning applies nothing.
//
// Skipped (not failed) when the viewer was not built or xvfb-run is missing.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <mutex>
#include <sstream>
#include <thread>

#include "common/dds/endpoint.hpp"
#include "common/util/clock.hpp"
#include "teleop/idl/DevicePubSubTypes.h"
#include "teleop/idl/TeleopPubSubTypes.h"
#include "tests/support/domains.hpp"
#include "tests/support/integration.hpp"
#include "tests/support/process.hpp"

namespace teleop::test {
namespace {

std::string tmp(const std::string& name) { return temp_path("viewer_drive", name); }

std::string read_all(const std::string& path) {
  std::ifstream f(path);
  std::stringstream b;
  b << f.rdbuf();
  return b.str();
}

std::string find_xvfb_run() {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    const std::string p = (dir.empty() ? std::string(".") : dir) + "/xvfb-run";
    if (access(p.c_str(), X_OK) == 0) return p;
  }
  return "";
}

/// What the slave did: contact, deepest deformation, from the 1 kHz SlaveState.
struct SlaveWatch {
  explicit SlaveWatch(int domain)
      : participant(dds::ParticipantOptions{"loopback", domain, "drive-test"}),
        reader(participant, dds::topics::kSlaveState,
               [this](const SlaveState& s, const eprosima::fastdds::dds::SampleInfo&) {
                 ++states;
                 if (s.in_contact()) ++contact_states;
                 std::lock_guard<std::mutex> l(m);
                 max_deformation_m = std::max(max_deformation_m, s.deformation_m());
               }) {}
  double deformation() {
    std::lock_guard<std::mutex> l(m);
    return max_deformation_m;
  }
  dds::Participant participant;
  std::atomic<int> states{0}, contact_states{0};
  std::mutex m;
  double max_deformation_m = 0.0;
  dds::Reader<SlaveStatePubSubType> reader;
};

#ifdef TELEOP_HAVE_VIEWER
/// The viewer's input script: press 2 cm into the sphere, tune (one good request, two bad),
/// drag sideways, come up, save `picture`, quit.
void write_drive_script(const std::string& script, const std::string& picture) {
  std::ofstream f(script);
  f << "# press 1 cm into the ball, tune, drag sideways, come up\n"
       "1.0 key pagedown 0.2\n"
       "2.5 tune force_gain 1.5 ramp_s 0.5\n"
       "3.2 tune force_gain 1000\n"
       "3.6 tune master_stiffness_n_per_m 500\n"
       "4.0 drag 12 0 0.6\n"
       "5.0 key pageup 0.8\n"
       "6.2 snapshot "
    << picture
    << "\n"
       "6.5 quit\n";
}

/// A second driver (a hand 10 cm up) that writes device states from 4.5 s to 7 s, after the
/// viewer has become the driver, or until `stop`.
void run_rogue_driver(int domain, const std::atomic<bool>& stop) {
  dds::Participant rp(dds::ParticipantOptions{"loopback", domain, "rogue-driver"});
  dds::Writer<DeviceStatePubSubType> w(rp, dds::topics::kDeviceState);
  const auto t0 = now_ns();
  DeviceState s;
  s.position_m()[2] = 0.1;
  s.orientation_wxyz()[0] = 1.0;
  s.engaged(true);
  std::uint64_t seq = 1000000;
  while (!stop.load() && seconds_between(t0, now_ns()) < 7.0) {
    if (seconds_between(t0, now_ns()) > 4.5) {  // after the viewer has become the driver
      s.seq(++seq);
      s.time_ns(now_ns());
      w.write(s);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

/// The viewer: the scripted snapshot was written, it wrote device states at 1 kHz, got the
/// master's force back and its tuning answers (`dj`: its --drive-json), and the drag moved
/// the handle.
void expect_viewer_drove(const Process& viewer, const std::string& picture, const std::string& dj) {
  EXPECT_NE(viewer.err().find("saved " + picture), std::string::npos) << viewer.err();
  std::ifstream png(picture, std::ios::binary | std::ios::ate);
  EXPECT_GT(static_cast<long>(png.tellg()), 10000L);
  EXPECT_GT(json_value(dj, "states_written"), 3000.0);
  EXPECT_GT(json_value(dj, "commands_received"), 3000.0);
  EXPECT_GT(json_value(dj, "max_force_n"), 0.5);  // pressed into the ball: felt it
  EXPECT_LT(json_value(dj, "max_force_n"), 10.0);
  EXPECT_EQ(json_nested(dj, "status", "accepted_count"), 1.0);
  EXPECT_EQ(json_nested(dj, "status", "rejected_count"), 2.0);
  EXPECT_DOUBLE_EQ(json_nested(dj, "status", "force_gain"), 1.5);
  // the drag moved the handle sideways (device frame; the keys only move it along z)
  const std::size_t fp = dj.find("\"final_position_m\": [");
  ASSERT_NE(fp, std::string::npos);
  double x = 0, y = 0, z = 0;
  ASSERT_EQ(std::sscanf(dj.c_str() + fp, "\"final_position_m\": [%lf, %lf, %lf]", &x, &y, &z), 3);
  EXPECT_GT(std::hypot(x, y), 0.01);
  EXPECT_NEAR(z, 0.03, 0.002);  // 0.2 s down and 0.8 s up at 0.05 m/s
}

/// The master: three requests, one applied, two rejected with their reasons, the second
/// driver ignored, no force step, the silence after the viewer quit reported.
void expect_master_tuned_and_held(const Process& master, const std::string& master_json) {
  const std::string mj = read_all(master_json);
  SCOPED_TRACE(mj);
  EXPECT_EQ(json_nested(mj, "tuning", "received"), 3.0);
  EXPECT_EQ(json_nested(mj, "tuning", "applied"), 1.0);
  EXPECT_EQ(json_nested(mj, "tuning", "rejected"), 2.0);
  EXPECT_DOUBLE_EQ(json_nested(mj, "in_force", "force_gain"), 1.5);
  EXPECT_NE(master.err().find("force_gain = 1000 is outside [0, 10]"), std::string::npos);
  EXPECT_NE(master.err().find("master_stiffness_n_per_m is not used by the force-position"),
            std::string::npos);
  EXPECT_NE(master.err().find("force_gain 1 -> 1.5 over 0.5 s"), std::string::npos);
  // the second driver's samples were ignored, counted, and said once
  EXPECT_GT(json_value(mj, "device_samples_ignored"), 50.0);
  EXPECT_NE(master.err().find("ignoring teleop/device_state from a second driver"),
            std::string::npos);
  // the session starts in contact (the keys pressed during homing): the force fades in
  // (Safety.FadeInAfterAReHomingStartsFromZero checks the shape). Here, live, the largest change
  // in one cycle stays within the device's rate bound; how close it comes depends on scheduling
  // (a slave state that arrives late after a server overrun jumps by what the slave moved
  // meanwhile: 0.86 N measured on a loaded 2-core machine, under 0.25 N on an idle one)
  EXPECT_LE(json_nested(mj, "safety", "max_step_n"),
            json_nested(mj, "safety", "max_force_rate_n_per_s") * 1e-3 + 1e-9);
  EXPECT_GT(json_nested(mj, "safety", "max_force_rate_n_per_s"), 0.0);
  EXPECT_EQ(json_nested(mj, "server", "faults"), 0.0);
  EXPECT_EQ(json_text(mj, "verdict"), "degraded");
  EXPECT_NE(mj.find("the device fell silent"), std::string::npos);
  EXPECT_GE(json_nested(mj, "driver", "silences"), 1.0);
  EXPECT_GT(json_nested(mj, "driver", "silent_s"), 1.0);
  EXPECT_NE(master.err().find("device silent"), std::string::npos);
}

TEST(ViewerDrive, ScriptedInputDrivesTheSlaveAndTunesTheMasterLive) {
  const std::string xvfb = find_xvfb_run();
  if (xvfb.empty()) GTEST_SKIP() << "xvfb-run not found (apt-get install xvfb xauth)";
  const int domain = domains::kViewerDrive;
  const std::string d = std::to_string(domain);
  const std::string script = tmp("script.txt");
  const std::string picture = tmp("drive.png");
  std::remove(picture.c_str());
  write_drive_script(script, picture);
  Process server(kServerBinary, {"--domain", d, "--quiet"}, "drive_server");
  SlaveWatch watch(domain);
  const std::string master_json = tmp("master.json"), drive_json = tmp("drive.json");
  Process master(kMasterBinary,
                 {"--domain", d, "--device", "external", "--accept-tuning", "--duration", "12",
                  "--summary-json", master_json},
                 "drive_master");
  Process viewer(xvfb,
                 {"-a",
                  "-n",
                  std::to_string(100 + domain),
                  "-s",
                  "-screen 0 960x540x24",
                  kViewerBinary,
                  "--domain",
                  d,
                  "--drive",
                  "--input-script",
                  script,
                  "--drive-json",
                  drive_json,
                  "--duration",
                  "40",
                  "--fps",
                  "20",
                  "--width",
                  "960",
                  "--height",
                  "540"},
                 "drive_viewer");
  // a second driver joins while the viewer drives: its samples must be ignored
  std::atomic<bool> stop_rogue{false};
  std::thread rogue([&] { run_rogue_driver(domain, stop_rogue); });
  const int viewer_rc = viewer.wait_for(60.0);
  stop_rogue = true;
  rogue.join();
  ASSERT_EQ(viewer_rc, 0) << viewer.err();
  // the viewer quits (6.5 s into its script) while the master runs on (12 s): the device falls
  // silent, the master holds and reports it, and the session is degraded (exit status 5)
  ASSERT_EQ(master.wait_for(40.0), 5) << master.err();
  server.signal(SIGINT);
  server.wait_for(10.0);

  const std::string dj = read_all(drive_json);
  SCOPED_TRACE(dj);
  ASSERT_NO_FATAL_FAILURE(expect_viewer_drove(viewer, picture, dj));
  expect_master_tuned_and_held(master, master_json);
  // the slave: it touched the ball and dented it
  EXPECT_GT(watch.states.load(), 5000);
  EXPECT_GT(watch.contact_states.load(), 300);
  EXPECT_GT(watch.deformation(), 0.002);
}
#endif

TEST(ViewerDrive, AMasterWithoutAcceptTuningAppliesNoRequestAndSaysSo) {
  const int domain = domains::kTuningRefused;
  const std::string d = std::to_string(domain);
  Process server(kServerBinary, {"--domain", d, "--quiet"}, "tuning_server");
  dds::Participant p(dds::ParticipantOptions{"loopback", domain, "tuning-test"});
  std::mutex m;
  bool have_status = false, accepting = true;
  dds::Reader<TuningStatusPubSubType> status(
      p, dds::topics::kTuningStatus,
      [&](const TuningStatus& s, const eprosima::fastdds::dds::SampleInfo&) {
        std::lock_guard<std::mutex> l(m);
        have_status = true;
        accepting = s.accepting();
      });
  dds::Writer<TuningRequestPubSubType> writer(p, dds::topics::kTuning);
  const std::string master_json = tmp("refusing_master.json");
  Process master(
      kMasterBinary,
      {"--domain", d, "--script", "hold", "--duration", "3", "--summary-json", master_json},
      "tuning_master");
  std::uint64_t seq = 0;
  for (int i = 0; i < 150; ++i) {  // until the master exits (about 5 s), at most 30 s
    TuningRequest r;
    r.seq(++seq);
    r.source("test");
    r.fields(4);  // force_gain: a force-position gain, within range
    r.force_gain(2.0);
    r.ramp_s(0.1);
    writer.write(r);
    if (master.wait_for(0.2) != -1) break;
  }
  ASSERT_EQ(master.wait_for(30.0), 0) << master.err();
  server.signal(SIGINT);
  server.wait_for(10.0);
  {
    std::lock_guard<std::mutex> l(m);
    EXPECT_TRUE(have_status);
    EXPECT_FALSE(accepting);
  }
  EXPECT_GT(seq, 10u);
  const std::string mj = read_all(master_json);
  SCOPED_TRACE(mj);
  EXPECT_NE(mj.find("\"accepting\": false"), std::string::npos);
  EXPECT_EQ(json_nested(mj, "tuning", "received"), 0.0);
  EXPECT_EQ(json_nested(mj, "tuning", "applied"), 0.0);
  EXPECT_DOUBLE_EQ(json_nested(mj, "in_force", "force_gain"), 1.0);
}

}  // namespace
}  // namespace teleop::test
