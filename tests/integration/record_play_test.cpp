// teleop_record and teleop_play: a server + master session recorded without loss (the
// recorder's counts against what the writers sent), then played back to a subscriber.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <thread>

#include "common/dds/endpoint.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"
#include "tests/support/domains.hpp"
#include "tests/support/integration.hpp"
#include "tests/support/process.hpp"

namespace teleop::test {
namespace {

const std::string kRecordBinary = std::string(TELEOP_BINARY_DIR) + "/client/teleop_record";
const std::string kPlayBinary = std::string(TELEOP_BINARY_DIR) + "/client/teleop_play";
const std::string kExperimentBinary = std::string(TELEOP_BINARY_DIR) + "/server/teleop_experiment";

std::string tmp(const std::string& name) { return temp_path("rec", name); }

/// Waits up to timeout_s for `needle` in a process's stdout.
bool wait_for_output(const Process& p, const std::string& needle, double timeout_s) {
  for (int i = 0; i < static_cast<int>(timeout_s * 50); ++i) {
    if (p.out().find(needle) != std::string::npos) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

double topic_field(const std::string& json, const std::string& topic, const std::string& field) {
  return json_nested(json, "teleop/" + topic, field);
}

TEST(RecordPlay, SessionRecordedWithoutLossThenPlayedBack) {
  const std::string d = std::to_string(domains::kRecordSession);
  const std::string rec_file = tmp("session.db"), rec_json = tmp("rec.json");
  const std::string master_json = tmp("master.json"), server_json = tmp("server.json");
  Process recorder(kRecordBinary, {"--domain", d, "--out", rec_file, "--summary-json", rec_json},
                   "rec_recorder");
  ASSERT_TRUE(wait_for_output(recorder, "recording", 20.0)) << recorder.err();
  Process server(kServerBinary,
                 {"--domain", d, "--duration", "60", "--summary-json", server_json, "--scene",
                  scene_file("tool_only.yaml")},
                 "rec_server");
  Process master(kMasterBinary,
                 {"--domain", d, "--duration", "2", "--homing", "0.5", "--summary-json",
                  master_json, "--quiet"},
                 "rec_master");
  ASSERT_EQ(master.wait_for(60.0), 0) << master.err();
  server.signal(SIGTERM);
  ASSERT_EQ(server.wait_for(20.0), 0) << server.err();
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // last samples in flight
  recorder.signal(SIGINT);
  ASSERT_EQ(recorder.wait_for(20.0), 0) << recorder.err();

  const std::string rec = Process::slurp(rec_json);
  const std::string m = Process::slurp(master_json);
  const std::string s = Process::slurp(server_json);
  const double sent = json_value(m, "sent");
  const double steps = json_value(s, "steps");
  const double cmd = topic_field(rec, "master_command", "samples");
  const double cmd_before = topic_field(rec, "master_command", "before_first");
  const double st = topic_field(rec, "slave_state", "samples");
  const double st_before = topic_field(rec, "slave_state", "before_first");
  std::printf(
      "[ recorded ] master_command %.0f (+%.0f written before the recorder matched the "
      "writer) of %.0f sent; slave_state %.0f (+%.0f) of %.0f steps; gaps %.0f, "
      "dropped %.0f; master rtt p99 with the recorder %.3f ms\n",
      cmd, cmd_before, sent, st, st_before, steps, json_value(rec, "gaps"),
      json_value(rec, "dropped"), json_nested(m, "rtt_ms", "p99"));
  // every sample a writer sent after the recorder matched it is in the file
  EXPECT_EQ(json_value(rec, "gaps"), 0.0) << rec;
  EXPECT_EQ(json_value(rec, "dropped"), 0.0) << rec;
  EXPECT_GT(cmd, 0.0) << rec;
  // the session's commands and the master's release of the slave at the end
  EXPECT_EQ(cmd + cmd_before, sent + json_value(m, "releases_sent")) << rec << m;
  EXPECT_EQ(st + st_before, steps) << rec << s;
  EXPECT_EQ(topic_field(rec, "scene", "samples"), 1.0) << rec;
  EXPECT_GT(topic_field(rec, "events", "samples"), 0.0) << rec;
  EXPECT_GT(topic_field(rec, "server_stats", "samples"), 0.0) << rec;

  // play it back at 4x to a subscriber on another domain
  {
    const int pd = domains::kPlayback;
    dds::Participant p(dds::ParticipantOptions{"loopback", pd, "playback-subscriber"});
    std::atomic<std::uint64_t> states{0}, scenes{0}, commands{0};
    dds::Reader<SlaveStatePubSubType> r_state(
        p, dds::topics::kSlaveState, dds::TopicQos::kStream,
        [&](const SlaveState&, const eprosima::fastdds::dds::SampleInfo&) { ++states; });
    dds::Reader<MasterCommandPubSubType> r_cmd(
        p, dds::topics::kMasterCommand, dds::TopicQos::kStream,
        [&](const MasterCommand&, const eprosima::fastdds::dds::SampleInfo&) { ++commands; });
    dds::Reader<SceneDescriptionPubSubType> r_scene(
        p, dds::topics::kScene, dds::TopicQos::kLatched,
        [&](const SceneDescription& sd, const eprosima::fastdds::dds::SampleInfo&) {
          if (sd.name() == "tool-only") ++scenes;
        });
    Process player(kPlayBinary,
                   {rec_file, "--domain", std::to_string(pd), "--speed", "4", "--wait", "1",
                    "--linger", "0.5"},
                   "rec_player");
    ASSERT_EQ(player.wait_for(60.0), 0) << player.err();
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    std::printf("[ played   ] slave_state %llu of %.0f, master_command %llu of %.0f, scene %llu\n",
                static_cast<unsigned long long>(states.load()), st,
                static_cast<unsigned long long>(commands.load()), cmd,
                static_cast<unsigned long long>(scenes.load()));
    EXPECT_NE(player.out().find("0 refused"), std::string::npos) << player.out();
    EXPECT_EQ(scenes.load(), 1u);
    // best effort over loopback: most, not necessarily all, arrive
    EXPECT_GE(static_cast<double>(states.load()), 0.5 * st);
    EXPECT_GE(static_cast<double>(commands.load()), 0.5 * cmd);
  }

  // bad flags exit 2 naming the flag, its value and the allowed range
  Process bad_speed(kPlayBinary, {rec_file, "--speed", "500"}, "rec_bad_speed");
  EXPECT_EQ(bad_speed.wait_for(20.0), 2);
  EXPECT_NE(bad_speed.err().find("--speed"), std::string::npos) << bad_speed.err();
  EXPECT_NE(bad_speed.err().find("500"), std::string::npos) << bad_speed.err();
  Process bad_seek(kPlayBinary,
                   {rec_file, "--seek", "1000", "--domain", std::to_string(domains::kPlayback)},
                   "rec_bad_seek");
  EXPECT_EQ(bad_seek.wait_for(20.0), 2);
  EXPECT_NE(bad_seek.err().find("--seek"), std::string::npos) << bad_seek.err();
  std::remove(rec_file.c_str());
}

/// The "hash XXXX" a resim run printed, or "".
std::string resim_hash(const std::string& out) {
  const auto at = out.find("hash ");
  return at == std::string::npos ? std::string() : out.substr(at + 5, 16);
}

// Issue 15 part 2: a recorded session re-runs off-line bit-identically from its command stream,
// and the master's own log drives a new session through --device replay unchanged.
TEST(RecordPlay, RecordedSessionReSimulatesBitIdenticallyAndItsLogReplays) {
  const std::string d = std::to_string(domains::kResimSession);
  const std::string rec_file = tmp("resim.db"), log = tmp("resim_master_log.csv");
  const std::string stream = tmp("resim_stream.csv"), scene = scene_file("default.yaml");
  {
    Process recorder(kRecordBinary, {"--domain", d, "--out", rec_file}, "resim_recorder");
    ASSERT_TRUE(wait_for_output(recorder, "recording", 20.0)) << recorder.err();
    Process server(kServerBinary, {"--domain", d, "--duration", "60", "--scene", scene},
                   "resim_server");
    Process master(kMasterBinary,
                   {"--domain", d, "--duration", "4", "--homing", "0.5", "--log", log, "--quiet"},
                   "resim_master");
    ASSERT_EQ(master.wait_for(60.0), 0) << master.err();
    server.signal(SIGTERM);
    ASSERT_EQ(server.wait_for(20.0), 0) << server.err();
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    recorder.signal(SIGINT);
    ASSERT_EQ(recorder.wait_for(20.0), 0) << recorder.err();
  }
  Process exporter(kPlayBinary, {rec_file, "--export-commands", stream}, "resim_export");
  ASSERT_EQ(exporter.wait_for(30.0), 0) << exporter.err();
  EXPECT_NE(exporter.out().find("commands -> " + stream), std::string::npos) << exporter.out();

  std::string hashes[2];
  for (int run = 0; run < 2; ++run) {
    Process resim(kExperimentBinary,
                  {"resim", "--commands", stream, "--scene", scene, "--out",
                   tmp("resim_out" + std::to_string(run)), "--no-chart"},
                  "resim_run" + std::to_string(run));
    ASSERT_EQ(resim.wait_for(120.0), 0) << resim.err() << resim.out();
    hashes[run] = resim_hash(resim.out());
    std::printf("[ resim    ] %s", resim.out().c_str());
    // every recorded command decoded; the session's commands were accepted (none stale: one
    // master, in order)
    EXPECT_NE(resim.out().find(" 0 undecodable, 0 refused: not the owner) from 1 owner(s)"),
              std::string::npos)
        << resim.out();
  }
  ASSERT_EQ(hashes[0].size(), 16u);
  EXPECT_EQ(hashes[0], hashes[1]);
  const std::string states = Process::slurp(tmp("resim_out0") + "/resim_states.csv");
  EXPECT_GT(std::count(states.begin(), states.end(), '\n'), 3000);

  // the master log as a --device replay file, unchanged
  Process server(kServerBinary, {"--domain", d, "--duration", "60", "--scene", scene},
                 "resim_replay_server");
  const std::string replay_json = tmp("resim_replay.json");
  Process replay(kMasterBinary,
                 {"--domain", d, "--duration", "2", "--homing", "0.5", "--device", "replay",
                  "--replay", log, "--summary-json", replay_json, "--quiet"},
                 "resim_replay_master");
  EXPECT_EQ(replay.wait_for(60.0), 0) << replay.err();
  server.signal(SIGTERM);
  server.wait_for(20.0);
  const std::string r = Process::slurp(replay_json);
  EXPECT_GT(json_value(r, "received"), 0.0) << r << replay.err();
  std::remove(rec_file.c_str());
}

}  // namespace
}  // namespace teleop::test
