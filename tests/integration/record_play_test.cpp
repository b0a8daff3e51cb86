// teleop_record and teleop_play: a server + master session recorded without loss (the
// recorder's counts against what the writers sent), then played back to a subscriber.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <set>
#include <thread>
#include <tuple>

#include "common/dds/endpoint.hpp"
#include "common/record/recording.hpp"
#include "common/util/version.hpp"
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

/// A server + master session (2 s) on domain `d`, recorded to `rec_file`; the three
/// summaries to their files.
void record_session(const std::string& d, const std::string& rec_file, const std::string& rec_json,
                    const std::string& master_json, const std::string& server_json) {
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
}

/// Plays `rec_file` back at 4x to a subscriber on another domain: the scene once, at least
/// half of the `st` slave states and `cmd` commands recorded (best effort over loopback).
void expect_played_back(const std::string& rec_file, double st, double cmd) {
  const int pd = domains::kPlayback;
  dds::Participant p(dds::ParticipantOptions{"loopback", pd, "playback-subscriber"});
  std::atomic<std::uint64_t> states{0}, scenes{0}, commands{0};
  dds::Reader<SlaveStatePubSubType> r_state(
      p, dds::topics::kSlaveState,
      [&](const SlaveState&, const eprosima::fastdds::dds::SampleInfo&) { ++states; });
  dds::Reader<MasterCommandPubSubType> r_cmd(
      p, dds::topics::kMasterCommand,
      [&](const MasterCommand&, const eprosima::fastdds::dds::SampleInfo&) { ++commands; });
  dds::Reader<SceneDescriptionPubSubType> r_scene(
      p, dds::topics::kScene,
      [&](const SceneDescription& sd, const eprosima::fastdds::dds::SampleInfo&) {
        if (sd.name() == "tool-only") ++scenes;
      });
  Process player(
      kPlayBinary,
      {rec_file, "--domain", std::to_string(pd), "--speed", "4", "--wait", "1", "--linger", "0.5"},
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

/// Bad flags exit 2 naming the flag, its value and the allowed range.
void expect_bad_play_flags_refused(const std::string& rec_file) {
  Process bad_speed(kPlayBinary, {rec_file, "--speed", "500"}, "rec_bad_speed");
  EXPECT_EQ(bad_speed.wait_for(20.0), 2);
  EXPECT_NE(bad_speed.err().find("--speed"), std::string::npos) << bad_speed.err();
  EXPECT_NE(bad_speed.err().find("500"), std::string::npos) << bad_speed.err();
  Process bad_seek(kPlayBinary,
                   {rec_file, "--seek", "1000", "--domain", std::to_string(domains::kPlayback)},
                   "rec_bad_seek");
  EXPECT_EQ(bad_seek.wait_for(20.0), 2);
  EXPECT_NE(bad_seek.err().find("--seek"), std::string::npos) << bad_seek.err();
}

TEST(RecordPlay, SessionRecordedWithoutLossThenPlayedBack) {
  const std::string d = std::to_string(domains::kRecordSession);
  const std::string rec_file = tmp("session.db"), rec_json = tmp("rec.json");
  const std::string master_json = tmp("master.json"), server_json = tmp("server.json");
  ASSERT_NO_FATAL_FAILURE(record_session(d, rec_file, rec_json, master_json, server_json));

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

  ASSERT_NO_FATAL_FAILURE(expect_played_back(rec_file, st, cmd));
  expect_bad_play_flags_refused(rec_file);
  std::remove(rec_file.c_str());
}

/// The "hash XXXX" a resim run printed, or "".
std::string resim_hash(const std::string& out) {
  const auto at = out.find("hash ");
  return at == std::string::npos ? std::string() : out.substr(at + 5, 16);
}

// A recorded session re-runs off-line bit-identically from its command stream,
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

/// Now on the system clock [ns] (the clock of DDS receive times).
std::int64_t wall_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

/// Every sample of a recording: (topic name, writer GUID, writer sequence number) -> payload.
using SampleKey = std::tuple<std::string, std::string, std::int64_t>;
std::map<SampleKey, std::vector<std::uint8_t>> samples_of(const std::string& path) {
  record::RecordingReader r(path);
  std::map<int, std::string> names;
  for (const auto& t : r.topics()) names[t.id] = t.name;
  std::map<SampleKey, std::vector<std::uint8_t>> out;
  record::RecordedSample s;
  r.scan(r.first_ns());
  while (r.next(s)) {
    const std::string guid(reinterpret_cast<const char*>(s.writer_guid), 16);
    out[{names[s.topic_id], guid, s.writer_seq}] = s.payload;
  }
  return out;
}

/// The value of the top-level "samples" of a recorder's --summary-json (after its topics).
double total_samples(const std::string& json) {
  const auto j = parse_json(json);
  return j.is_object() && j.contains("samples") && j["samples"].is_number()
             ? j["samples"].get<double>()
             : -1.0;
}

/// One live session on domain `d` recorded twice: to `full` (finished normally) and to
/// `killed` (0.5 s chunks, killed with -9 after 3 s, the time of the kill in `killed_at_ns`).
void record_twice_one_killed(const std::string& d, const std::string& full,
                             const std::string& killed, const std::string& rec_json,
                             const std::string& scene, std::int64_t& killed_at_ns) {
  Process recorder(kRecordBinary, {"--domain", d, "--out", full, "--summary-json", rec_json},
                   "mcap_recorder");
  Process victim(kRecordBinary, {"--domain", d, "--out", killed, "--chunk-s", "0.5"},
                 "mcap_victim");
  ASSERT_TRUE(wait_for_output(recorder, "(mcap)", 20.0)) << recorder.err();
  ASSERT_TRUE(wait_for_output(victim, "(mcap)", 20.0)) << victim.err();
  Process server(kServerBinary, {"--domain", d, "--duration", "60", "--scene", scene},
                 "mcap_server");
  Process master(kMasterBinary, {"--domain", d, "--duration", "4", "--homing", "0.5", "--quiet"},
                 "mcap_master");
  std::this_thread::sleep_for(std::chrono::milliseconds(3000));
  victim.signal(SIGKILL);
  killed_at_ns = wall_ns();
  EXPECT_EQ(victim.wait_for(10.0), -2);
  ASSERT_EQ(master.wait_for(60.0), 0) << master.err();
  server.signal(SIGTERM);
  ASSERT_EQ(server.wait_for(20.0), 0) << server.err();
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  recorder.signal(SIGINT);
  ASSERT_EQ(recorder.wait_for(20.0), 0) << recorder.err();
}

/// The killed recorder's file: recovered, each of its samples as the finished file (`whole`)
/// has it, and what it lost is the end of the session: the open chunk (--chunk-s 0.5) and the
/// queue.
void expect_killed_file_recovered(const std::string& killed,
                                  const std::map<SampleKey, std::vector<std::uint8_t>>& whole,
                                  std::int64_t killed_at_ns) {
  record::RecordingReader r(killed);
  const record::RecordingHealth h = r.health();
  EXPECT_TRUE(h.recovered) << h.how;
  EXPECT_GT(h.chunks, 0u) << h.note;
  const auto got = samples_of(killed);
  // the first sequence number the finished recorder heard from each writer: a recorder that
  // matched a writer sooner holds its earlier samples too
  std::map<std::pair<std::string, std::string>, std::int64_t> first_seq;
  for (const auto& [key, payload] : whole) {
    const auto w = std::make_pair(std::get<0>(key), std::get<1>(key));
    if (!first_seq.count(w)) first_seq[w] = std::get<2>(key);
  }
  std::size_t same = 0, earlier = 0;
  for (const auto& [key, payload] : got) {
    const auto it = whole.find(key);
    const auto w = first_seq.find(std::make_pair(std::get<0>(key), std::get<1>(key)));
    if (it != whole.end()) {
      same += it->second == payload ? 1 : 0;
    } else if (w == first_seq.end() || std::get<2>(key) < w->second) {
      ++earlier;
    }
  }
  EXPECT_EQ(same + earlier, got.size()) << same << " the same, " << earlier << " earlier";
  const double lost_s = static_cast<double>(killed_at_ns - r.last_ns()) * 1e-9;
  std::printf(
      "[ kill -9  ] recovered %zu samples in %llu chunks; the last was received %.3f s "
      "before the kill; dropped %llu bytes (%llu chunk, %llu messages seen in it)\n",
      got.size(), static_cast<unsigned long long>(h.chunks), lost_s,
      static_cast<unsigned long long>(h.dropped_bytes),
      static_cast<unsigned long long>(h.dropped_chunks),
      static_cast<unsigned long long>(h.dropped_messages));
  // a bound for a loaded 2-core machine: --chunk-s 0.5 plus the queue, several times over
  EXPECT_LT(lost_s, 5.0);
  EXPECT_GT(got.size(), 1000u);
}

/// `full` played back from 1 s on to a subscriber on another domain (as the SQLite test does).
void expect_mcap_played_back(const std::string& full) {
  const int pd = domains::kPlaybackMcap;
  dds::Participant p(dds::ParticipantOptions{"loopback", pd, "mcap-playback-subscriber"});
  std::atomic<std::uint64_t> states{0}, scenes{0};
  dds::Reader<SlaveStatePubSubType> r_state(
      p, dds::topics::kSlaveState,
      [&](const SlaveState&, const eprosima::fastdds::dds::SampleInfo&) { ++states; });
  dds::Reader<SceneDescriptionPubSubType> r_scene(
      p, dds::topics::kScene,
      [&](const SceneDescription&, const eprosima::fastdds::dds::SampleInfo&) { ++scenes; });
  Process player(kPlayBinary,
                 {full, "--domain", std::to_string(pd), "--speed", "4", "--wait", "1", "--linger",
                  "0.5", "--seek", "1"},
                 "mcap_player");
  ASSERT_EQ(player.wait_for(60.0), 0) << player.err();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_NE(player.out().find("0 refused"), std::string::npos) << player.out();
  EXPECT_EQ(scenes.load(), 1u);  // the latched scene, recorded before the seek point
  EXPECT_GT(states.load(), 500u);
}

/// Re-simulated straight from the MCAP file, and from its exported command stream: the same.
void expect_resim_from_file_and_stream_agree(const std::string& full, const std::string& stream,
                                             const std::string& scene) {
  Process exporter(kPlayBinary, {full, "--export-commands", stream}, "mcap_export");
  ASSERT_EQ(exporter.wait_for(60.0), 0) << exporter.err();
  std::string hashes[2];
  const std::vector<std::vector<std::string>> sources = {{"--recording", full},
                                                         {"--commands", stream}};
  for (int run = 0; run < 2; ++run) {
    std::vector<std::string> args = {
        "resim", "--scene", scene, "--out", tmp("mcap_resim" + std::to_string(run)), "--no-chart"};
    args.insert(args.end(), sources[run].begin(), sources[run].end());
    Process resim(kExperimentBinary, args, "mcap_resim" + std::to_string(run));
    ASSERT_EQ(resim.wait_for(120.0), 0) << resim.err() << resim.out();
    std::printf("[ resim    ] %s", resim.out().c_str());
    hashes[run] = resim_hash(resim.out());
  }
  ASSERT_EQ(hashes[0].size(), 16u);
  EXPECT_EQ(hashes[0], hashes[1]);
}

/// A window of the recording, found through its chunk index; one outside it refused.
void expect_resim_window(const std::string& full, const std::string& scene) {
  Process window(kExperimentBinary,
                 {"resim", "--recording", full, "--from", "1", "--to", "2", "--scene", scene,
                  "--out", tmp("mcap_resim_window"), "--no-chart"},
                 "mcap_resim_window");
  ASSERT_EQ(window.wait_for(120.0), 0) << window.err() << window.out();
  const std::string summary = Process::slurp(tmp("mcap_resim_window") + "/resim_summary.csv");
  EXPECT_NE(summary.find("commands,"), std::string::npos) << summary;
  Process bad_window(kExperimentBinary,
                     {"resim", "--recording", full, "--from", "1000", "--scene", scene, "--out",
                      tmp("mcap_resim_bad"), "--no-chart"},
                     "mcap_resim_bad");
  EXPECT_EQ(bad_window.wait_for(60.0), 2);
  EXPECT_NE(bad_window.err().find("--from"), std::string::npos) << bad_window.err();
}

// The default format is MCAP. One live session, two recorders: one finishes
// normally (its file read through the summary, played back, converted, re-simulated from a
// window found through the chunk index), the other is killed with -9 mid-session (its file
// recovered: every complete chunk, each sample identical to the finished recording's).
TEST(RecordPlay, McapSessionPlaysReSimulatesAndSurvivesAKill) {
  const std::string d = std::to_string(domains::kRecordMcap);
  const std::string full = tmp("session.mcap"), killed = tmp("killed.mcap");
  const std::string rec_json = tmp("mcap_rec.json"), scene = scene_file("tool_only.yaml");
  std::int64_t killed_at_ns = 0;
  ASSERT_NO_FATAL_FAILURE(record_twice_one_killed(d, full, killed, rec_json, scene, killed_at_ns));
  const std::string rec = Process::slurp(rec_json);
  EXPECT_NE(rec.find("\"format\": \"mcap\""), std::string::npos) << rec;
  EXPECT_EQ(json_value(rec, "gaps"), 0.0) << rec;
  EXPECT_EQ(json_value(rec, "dropped"), 0.0) << rec;

  // the finished file: read through its summary, every CRC checked
  Process info(kPlayBinary, {full, "--info"}, "mcap_info");
  ASSERT_EQ(info.wait_for(60.0), 0) << info.err();
  std::printf("[ info     ] %s", info.out().c_str());
  EXPECT_NE(info.out().find("read through its summary"), std::string::npos) << info.out();
  EXPECT_NE(info.out().find("whole file: ok"), std::string::npos) << info.out();
  const auto whole = samples_of(full);
  EXPECT_EQ(static_cast<double>(whole.size()), total_samples(rec)) << rec;
  // which build wrote it
  EXPECT_EQ(record::RecordingReader(full).meta().at("version"), version_string());

  expect_killed_file_recovered(killed, whole, killed_at_ns);
  Process killed_info(kPlayBinary, {killed, "--info"}, "mcap_killed_info");
  EXPECT_EQ(killed_info.wait_for(60.0), 0) << killed_info.err();
  EXPECT_NE(killed_info.out().find("recovered"), std::string::npos) << killed_info.out();

  ASSERT_NO_FATAL_FAILURE(expect_mcap_played_back(full));

  // converted to SQLite and back: the same samples
  const std::string db = tmp("converted.db"), back = tmp("back.mcap");
  Process to_db(kPlayBinary, {full, "--convert", db}, "mcap_to_db");
  ASSERT_EQ(to_db.wait_for(60.0), 0) << to_db.err();
  Process to_mcap(kPlayBinary, {db, "--convert", back}, "mcap_back");
  ASSERT_EQ(to_mcap.wait_for(60.0), 0) << to_mcap.err();
  EXPECT_TRUE(samples_of(db) == whole);
  EXPECT_TRUE(samples_of(back) == whole);

  const std::string stream = tmp("mcap_stream.csv");
  ASSERT_NO_FATAL_FAILURE(expect_resim_from_file_and_stream_agree(full, stream, scene));
  ASSERT_NO_FATAL_FAILURE(expect_resim_window(full, scene));
  // the killed recorder's shared-memory segments
  if (std::system("fastdds shm clean >/dev/null 2>&1") != 0)
    std::printf("fastdds shm clean failed\n");
  for (const auto& f : {full, killed, db, back, stream}) std::remove(f.c_str());
}

}  // namespace
}  // namespace teleop::test
