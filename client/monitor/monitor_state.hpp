#pragma once
// What teleop_monitor knows about a session, and how it shows it: per-topic counts, rates and
// ages on the monitor's own clock, the newest value of each state topic, a ring of recent
// events. Three renderings: a screen refreshed in place (ANSI), the scrolling line log, and
// one JSON object per line. Pure functions of the snapshot, so they are unit-testable.
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::monitor {

/// One topic as seen by the monitor.
struct TopicView {
  std::string name;      ///< short name, e.g. "slave_state"
  bool latched = false;  ///< sent once (scene, topology): never stale
  double stale_after_s = 0.5;
  std::uint64_t count = 0;  ///< samples received
  double rate_hz = 0.0;     ///< over the last second
  double age_s = -1.0;      ///< since the newest sample; < 0: never received
  bool stale() const { return !latched && count > 0 && age_s > stale_after_s; }
  bool seen() const { return count > 0; }
};

struct EventView {
  double at_s = 0.0;  ///< monitor time when it arrived [s]
  Event event;
};

/// Everything one refresh shows.
struct Snapshot {
  double t_s = 0.0;  ///< since the monitor started [s]
  int domain = 0;
  std::string profile;
  bool insecure = false;  ///< the profile reaches beyond 127.0.0.1 without DDS Security
  /// Reading the full-rate topics (--full-rate) instead of the 10 Hz `_monitor` copies; then
  /// master_command is the master's own topic, else the server's count of commands received.
  bool full_rate = false;
  std::vector<TopicView> topics;  ///< in display order
  bool have_scene = false;
  SceneDescription scene;
  bool have_slave = false, have_master = false, have_stats = false;
  bool have_experiment = false;  ///< a teleop/experiment description arrived (latched)
  ExperimentDescription experiment;
  SlaveState slave;
  MasterState master;
  ServerStats stats;
  std::deque<EventView> events;  ///< newest last
  /// The server watched: GUID prefix of the participant whose slave_state is shown ("" none),
  /// and how many participants have written slave_state or server_stats (more than one: a
  /// second server or a rogue on this domain).
  std::string server;
  int servers = 0;

  const TopicView* topic(const std::string& name) const;
  /// Nothing from a server yet (no slave_state, server_stats or scene).
  bool waiting() const;
  /// One status line: LIVE, waiting for a server, or the server gone silent.
  std::string status() const;
};

/// A JSON string literal (quotes and escapes).
std::string json_string(const std::string& s);

/// The screen: `rows` x `cols` lines without escapes (the caller adds cursor control).
std::vector<std::string> render_screen(const Snapshot& s, int rows, int cols);
/// The line log of one period (the format teleop_monitor always printed, with STALE marks).
std::string render_lines(const Snapshot& s);
/// One JSON object (no newline) with the status of every topic and the newest values.
std::string render_json(const Snapshot& s);
/// One JSON object for an event / a scene.
std::string event_json(const EventView& e);
std::string scene_json(const SceneDescription& d);
/// The scene line printed when the scene arrives.
std::string scene_line(const SceneDescription& d);
/// One event as a text line.
std::string event_line(const EventView& e);
/// The experiment line: scheme, gains, injected delay, jitter and loss, the loop delay the
/// controller lives with, the device ("experiment (none yet: ...)" before a master wrote one).
std::string experiment_line(const Snapshot& s);
/// The experiment as a JSON object.
std::string experiment_json(const ExperimentDescription& e);

}  // namespace teleop::monitor
