// teleop_monitor: a terminal observer of a running session. Subscribes only (it never
// writes), so any number may join or leave without disturbing the loop.
//
//   teleop_monitor [--domain D] [--profile P] [--period S] [--duration S] [--stale S]
//                  [--json | --lines | --tui] [--full-rate] [--nice 19]
//
// By default it reads the 10 Hz copies of the hot topics (teleop/*_monitor, written off the
// loops' threads), so any number of monitors costs the 1 kHz loops nothing; the command rate is
// then the server's count of commands received (SlaveState.commands_received). --full-rate reads
// the 1 kHz topics themselves (and teleop/master_command), as earlier versions did. Like the
// viewer, it lowers its own priority (--nice, 19 by default) before any thread starts: on a
// machine shared with the server and the master, observers take only the CPU the loops leave.
//
// On a terminal it draws one screen refreshed in place (ANSI; q or Ctrl-C quits): the status
// (waiting for a server on domain D, live, or stale), every topic's rate, age and sample count,
// the newest slave, master and server figures, and the events as they arrive. Data older than
// --stale is marked STALE and its values are no longer shown as live. When stdout is not a
// terminal (or with --lines) it prints the scrolling log of earlier versions, one block per
// period; --json prints one JSON object per line (status every period, events and the scene as
// they arrive) for scripts. The monitor's rendering lives in client/monitor/.
#include <poll.h>
#include <signal.h>
#include <sys/ioctl.h>
#include <sys/resource.h>
#include <termios.h>
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <deque>
#include <iostream>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "client/monitor/monitor_state.hpp"
#include "common/config/config.hpp"
#include "common/config/flags.hpp"
#include "common/dds/endpoint.hpp"
#include "common/dds/guid_text.hpp"
#include "common/dds/network_flags.hpp"
#include "common/dds/observer_topics.hpp"
#include "common/util/clock.hpp"
#include "common/util/signals.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace {

using teleop::monitor::Snapshot;
using teleop::monitor::TopicView;

enum class Mode { kTui, kLines, kJson };

/// Counts and the newest sample time of one topic, written by its reader thread.
struct Counter {
  std::atomic<std::uint64_t> count{0};
  std::atomic<std::int64_t> last_ns{0};
  void hit() {
    last_ns.store(teleop::now_ns());
    count.fetch_add(1);
  }
};

/// Raw keyboard on a terminal stdin for the screen mode; restored on destruction.
class RawKeys {
 public:
  RawKeys() {
    if (!isatty(STDIN_FILENO) || tcgetattr(STDIN_FILENO, &saved_) != 0) return;
    termios raw = saved_;
    raw.c_lflag &= static_cast<tcflag_t>(~(ICANON | ECHO));
    raw.c_cc[VMIN] = 0;
    raw.c_cc[VTIME] = 0;
    active_ = tcsetattr(STDIN_FILENO, TCSANOW, &raw) == 0;
  }
  ~RawKeys() {
    if (active_) tcsetattr(STDIN_FILENO, TCSANOW, &saved_);
  }
  /// True if q was pressed.
  bool quit_pressed() {
    if (!active_) return false;
    pollfd p{STDIN_FILENO, POLLIN, 0};
    while (poll(&p, 1, 0) > 0 && (p.revents & POLLIN)) {
      char c = 0;
      if (read(STDIN_FILENO, &c, 1) != 1) return false;
      if (c == 'q' || c == 'Q') return true;
    }
    return false;
  }

 private:
  termios saved_{};
  bool active_ = false;
};

}  // namespace

namespace {

using namespace teleop;
namespace tdds = teleop::dds;
using Info = eprosima::fastdds::dds::SampleInfo;

struct Flags {
  std::optional<int> domain;
  std::optional<std::string> profile;
  std::optional<double> period;
  double duration_s = 0.0;
  double stale_s = 0.5;
  bool json = false, lines = false, tui = false;
  bool full_rate = false;
  int nice = 19;
  double reconnect_s = 3.0;
  tdds::NetworkFlags net;
};

void add_flags(CLI::App& app, Flags& f) {
  using teleop::config::add_integer;
  using teleop::config::add_number;
  add_integer(app, "--domain", f.domain, 0.0, 232.0,
              "DDS domain id (default: $TELEOP_DOMAIN or 0)");
  app.add_option("--profile", f.profile, "Fast DDS profile (default: loopback)");
  tdds::add_network_flags(app, f.net);
  add_number(app, "--period", f.period, 0.05, 60.0,
             "refresh / print period (default: 0.25 on the screen, 1 otherwise)", "s");
  add_number(app, "--duration", f.duration_s, 0.0, 1e7, "stop after this long (0 = until q/SIGINT)",
             "s");
  add_number(app, "--stale", f.stale_s, 0.05, 3600.0,
             "a stream topic silent this long is STALE (server_stats: at least 3 s)", "s")
      ->capture_default_str();
  auto* json_opt = app.add_flag("--json", f.json, "one JSON object per line, for scripts");
  auto* lines_opt = app.add_flag("--lines", f.lines, "scrolling text log (default off a terminal)");
  auto* tui_opt = app.add_flag("--tui", f.tui, "screen refreshed in place (default on a terminal)");
  app.add_flag("--full-rate", f.full_rate,
               "read the full-rate topics (slave_state 1 kHz, master_command, master_state, "
               "mesh_frame) instead of the 10 Hz *_monitor copies; loads the loops");
  add_integer(app, "--nice", f.nice, 0.0, 19.0,
              "scheduling niceness of the monitor (it yields the CPU to the server and master on "
              "the same machine)")
      ->capture_default_str();
  teleop::dds::add_reconnect_flag(app, f.reconnect_s);
  json_opt->excludes(lines_opt)->excludes(tui_opt);
  lines_opt->excludes(tui_opt);
}

/// The topics the monitor counts, in display order, with their counters.
struct TopicTable {
  struct Def {
    const char* name;
    bool latched;
    double stale;
  };
  explicit TopicTable(double stale_s)
      : defs{{"slave_state", false, stale_s},
             {"master_command", false, stale_s},
             {"master_state", false, stale_s},
             {"mesh_frame", false, stale_s},
             {"server_stats", false, std::max(stale_s, 3.0)},
             {"events", true, 0.0},
             {"scene", true, 0.0},
             {"experiment", true, 0.0},
             {"mesh_topology", true, 0.0}},
        counters(defs.size()) {}
  Counter& operator[](const char* n) {
    for (std::size_t i = 0; i < defs.size(); ++i) {
      if (std::string(defs[i].name) == n) return counters[i];
    }
    return counters[0];
  }
  std::vector<Def> defs;
  std::deque<Counter> counters;
};

void print_now(const std::string& text) {  // lines and json modes only
  std::fputs(text.c_str(), stdout);
  std::fputc('\n', stdout);
  std::fflush(stdout);
}

/// The readers of every topic the monitor shows; each fills the snapshot and counts its samples.
class Readers {
 public:
  Readers(tdds::Participant& p, const tdds::ObserverTopics& topics, Mode mode, std::int64_t t0,
          std::mutex& m, Snapshot& snap, TopicTable& table)
      : mode_(mode),
        t0_(t0),
        m_(m),
        snap_(snap),
        table_(table),
        slave_(
            p, topics.slave_state,
            [this, count_commands = !topics.master_command](const SlaveState& s, const Info& info) {
              note_server(info, true);
              on_slave(s, count_commands);
            }),
        master_(p, topics.master_state,
                [this](const MasterState& s, const Info&) {
                  std::lock_guard<std::mutex> l(m_);
                  snap_.master = s;
                  snap_.have_master = true;
                  table_["master_state"].hit();
                }),
        stats_(p, tdds::topics::kServerStats,
               [this](const ServerStats& s, const Info& info) {
                 note_server(info, false);
                 std::lock_guard<std::mutex> l(m_);
                 snap_.stats = s;
                 snap_.have_stats = true;
                 table_["server_stats"].hit();
               }),
        scene_(p, tdds::topics::kScene,
               [this](const SceneDescription& s, const Info&) { on_scene(s); }),
        topology_(p, tdds::topics::kMeshTopology,
                  [this](const MeshTopology&, const Info&) { table_["mesh_topology"].hit(); }),
        frames_(p, topics.mesh_frame,
                [this](const MeshFrame&, const Info&) { table_["mesh_frame"].hit(); }),
        events_(p, tdds::topics::kEvents, [this](const Event& e, const Info&) { on_event(e); }),
        experiment_(p, tdds::topics::kExperiment,
                    [this](const ExperimentDescription& e, const Info&) {
                      std::lock_guard<std::mutex> l(m_);
                      snap_.experiment = e;
                      snap_.have_experiment = true;
                      table_["experiment"].hit();
                    }) {
    if (topics.master_command) {
      command_.emplace(p, tdds::topics::kMasterCommand, [this](const MasterCommand&, const Info&) {
        table_["master_command"].hit();
      });
    }
  }

 private:
  /// Which participant writes the server's topics: the one whose slave_state is shown is the
  /// server watched; each other one is counted (a second server or a rogue).
  void note_server(const Info& info, bool state) {
    const auto& prefix = info.sample_identity.writer_guid().guidPrefix;
    std::lock_guard<std::mutex> l(m_);
    if (std::find(writers_.begin(), writers_.end(), prefix) == writers_.end()) {
      writers_.push_back(prefix);
      snap_.servers = static_cast<int>(writers_.size());
    }
    if (state) snap_.server = tdds::guid_prefix_text(prefix);
  }

  // without --full-rate, master_command's row is the server's count of commands received
  void on_slave(const SlaveState& s, bool count_commands) {
    std::lock_guard<std::mutex> l(m_);
    snap_.slave = s;
    snap_.have_slave = true;
    table_["slave_state"].hit();
    if (!count_commands) return;
    const std::uint64_t c = s.commands_received();
    if (!have_commands_base_ || c < commands_seen_) {  // first sample, or a new server
      have_commands_base_ = true;
      commands_seen_ = c;
      return;
    }
    if (c > commands_seen_) {
      Counter& cmd = table_["master_command"];
      cmd.last_ns.store(now_ns());
      cmd.count.fetch_add(c - commands_seen_);
      commands_seen_ = c;
    }
  }
  void on_scene(const SceneDescription& s) {
    std::lock_guard<std::mutex> l(m_);
    snap_.scene = s;
    snap_.have_scene = true;
    table_["scene"].hit();
    if (mode_ == Mode::kLines) print_now(monitor::scene_line(s));
    if (mode_ == Mode::kJson) print_now(monitor::scene_json(s));
  }
  void on_event(const Event& e) {
    std::lock_guard<std::mutex> l(m_);
    table_["events"].hit();
    monitor::EventView ev{seconds_between(t0_, now_ns()), e};
    snap_.events.push_back(ev);
    while (snap_.events.size() > 200) snap_.events.pop_front();
    if (mode_ == Mode::kLines) print_now(monitor::event_line(ev));
    if (mode_ == Mode::kJson) print_now(monitor::event_json(ev));
  }

  Mode mode_;
  std::int64_t t0_;
  std::mutex& m_;
  Snapshot& snap_;
  TopicTable& table_;
  std::vector<eprosima::fastrtps::rtps::GuidPrefix_t> writers_;
  bool have_commands_base_ = false;
  std::uint64_t commands_seen_ = 0;
  tdds::Reader<SlaveStatePubSubType> slave_;
  tdds::Reader<MasterStatePubSubType> master_;
  tdds::Reader<ServerStatsPubSubType> stats_;
  tdds::Reader<SceneDescriptionPubSubType> scene_;
  tdds::Reader<MeshTopologyPubSubType> topology_;
  tdds::Reader<MeshFramePubSubType> frames_;
  tdds::Reader<EventPubSubType> events_;
  tdds::Reader<ExperimentDescriptionPubSubType> experiment_;
  std::optional<tdds::Reader<MasterCommandPubSubType>> command_;
};

/// Counts at past refreshes, for the rate over the last second.
using History = std::deque<std::pair<std::int64_t, std::vector<std::uint64_t>>>;

/// The snapshot's topic rows at `now` (counts, rate over the last second, age).
void update_topics(Snapshot& snap, TopicTable& table, History& history, std::int64_t now) {
  std::vector<std::uint64_t> counts(table.defs.size());
  for (std::size_t i = 0; i < table.defs.size(); ++i) counts[i] = table.counters[i].count.load();
  history.emplace_back(now, counts);
  while (history.size() > 2 && seconds_between(history[1].first, now) >= 1.0) {
    history.pop_front();
  }
  const double window = seconds_between(history.front().first, now);
  snap.topics.clear();
  for (std::size_t i = 0; i < table.defs.size(); ++i) {
    TopicView t;
    t.name = table.defs[i].name;
    t.latched = table.defs[i].latched;
    t.stale_after_s = table.defs[i].stale;
    t.count = counts[i];
    t.rate_hz =
        window > 0.0 ? static_cast<double>(counts[i] - history.front().second[i]) / window : 0.0;
    const auto last = table.counters[i].last_ns.load();
    t.age_s = t.count > 0 ? seconds_between(last, now) : -1.0;
    snap.topics.push_back(t);
  }
}

void render(Mode mode, const Snapshot& snap) {
  if (mode == Mode::kJson) {
    print_now(monitor::render_json(snap));
    return;
  }
  if (mode == Mode::kLines) {
    std::fputs(monitor::render_lines(snap).c_str(), stdout);
    std::fflush(stdout);
    return;
  }
  winsize ws{};
  int rows = 40, cols = 160;
  if (ioctl(STDOUT_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_row > 0) {
    rows = ws.ws_row;
    cols = ws.ws_col;
  }
  std::string frame = "\x1b[H";
  for (const auto& line : monitor::render_screen(snap, rows - 1, cols)) {
    frame += line + "\x1b[K\n";
  }
  frame += "\x1b[J";
  std::fputs(frame.c_str(), stdout);
  std::fflush(stdout);
}

/// Sleeps until `next` (or a stop), polling the keyboard on the screen.
void wait_until(std::int64_t next, Mode mode, RawKeys& keys) {
  while (!stop_requested() && now_ns() < next) {
    if (keys.quit_pressed()) request_stop();
    // the screen polls the keyboard; the other modes only wait for the next period
    const std::int64_t step_ns = mode == Mode::kTui ? 20'000'000 : 100'000'000;
    std::this_thread::sleep_for(
        std::chrono::nanoseconds(std::max<std::int64_t>(0, std::min(step_ns, next - now_ns()))));
  }
}

/// The output mode the flags ask for (none: the screen on a terminal, else lines).
Mode output_mode(const Flags& f) {
  return f.json    ? Mode::kJson
         : f.lines ? Mode::kLines
         : f.tui   ? Mode::kTui
                   : (isatty(STDOUT_FILENO) ? Mode::kTui : Mode::kLines);
}

/// --nice applied (the flags' ranges were checked on their text).
void apply_nice(const Flags& f) {
  // before the participant: every DDS thread inherits the priority
  if (f.nice > 0 && setpriority(PRIO_PROCESS, 0, f.nice) != 0) {
    std::cerr << "teleop_monitor: warning: cannot lower the priority (--nice " << f.nice << ")\n";
  }
}

/// SIGINT and SIGTERM stop the monitor; so does SIGHUP (a closed terminal, or tmux kill-server).
void install_signal_handlers() {
  install_stop_signal_handlers();
  struct sigaction hup {};
  hup.sa_handler = [](int) { request_stop(); };
  sigemptyset(&hup.sa_mask);
  sigaction(SIGHUP, &hup, nullptr);
}

int run_monitor(Flags& f) {
  const Mode mode = output_mode(f);
  const double period_s = f.period ? *f.period : (mode == Mode::kTui ? 0.25 : 1.0);
  apply_nice(f);
  const auto opts = tdds::resolve_participant_options(f.profile, f.domain, "teleop_monitor", f.net);
  tdds::profile_file(opts.profile);
  tdds::ProfileKind kind = tdds::ProfileKind::kUdp;
  (void)tdds::participant_qos(opts, &kind);
  auto p = std::make_unique<tdds::Participant>(opts);
  install_signal_handlers();

  const auto t0 = now_ns();
  std::mutex m;  // guards snap's values, events and stdout
  Snapshot snap;
  snap.domain = opts.domain;
  snap.profile = opts.profile;
  snap.insecure = opts.insecure;
  snap.full_rate = f.full_rate;
  TopicTable table(f.stale_s);
  const tdds::ObserverTopics topics =
      tdds::observer_topics(tdds::ObserverKind::kMonitor, f.full_rate);
  auto readers = std::make_unique<Readers>(*p, topics, mode, t0, m, snap, table);
  // Fast DDS 2.9's TCP client has been seen (multi-host test, about one connection in eight)
  // never to complete its connection to a running server: with nothing from the server for
  // --reconnect seconds, a new participant makes a new connection
  bool may_reconnect = kind == tdds::ProfileKind::kTcp && f.reconnect_s > 0.0;
  auto connected_at = t0;
  RawKeys keys;
  if (mode == Mode::kTui) {
    std::fputs("\x1b[?1049h\x1b[?25l", stdout);  // alternate screen, hide the cursor
    std::fflush(stdout);
  }
  History history;
  auto next = t0;
  while (!stop_requested()) {
    next += static_cast<std::int64_t>(period_s * 1e9);
    wait_until(next, mode, keys);
    if (stop_requested()) break;
    const auto now = now_ns();
    if (may_reconnect && seconds_between(connected_at, now) > f.reconnect_s) {
      bool heard = false;
      {
        std::lock_guard<std::mutex> l(m);
        heard = snap.have_scene || snap.have_slave || snap.have_stats || snap.have_master;
      }
      if (heard) {
        may_reconnect = false;  // connected: a server that goes away later is shown as stale
      } else {
        readers.reset();
        p.reset();
        p = std::make_unique<tdds::Participant>(opts);
        readers = std::make_unique<Readers>(*p, topics, mode, t0, m, snap, table);
        connected_at = now_ns();
        if (mode != Mode::kTui) {
          std::cerr << "teleop_monitor: no answer from a server over TCP for " << f.reconnect_s
                    << " s: reconnecting\n";
        }
      }
    }
    std::lock_guard<std::mutex> l(m);
    snap.t_s = seconds_between(t0, now);
    update_topics(snap, table, history, now);
    render(mode, snap);
    if (f.duration_s > 0 && snap.t_s >= f.duration_s) break;
  }
  if (mode == Mode::kTui) {
    std::fputs("\x1b[?25h\x1b[?1049l", stdout);  // restore the screen and the cursor
    std::fflush(stdout);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"teleop_monitor: terminal observer of a teleoperation session"};
  Flags flags;
  add_flags(app, flags);
  if (const int status = teleop::config::parse_command_line(app, "teleop_monitor", argc, argv);
      status >= 0) {
    return status == 2 ? 2 : status;
  }
  try {
    return run_monitor(flags);
  } catch (const teleop::config::ConfigError& e) {
    std::cerr << "teleop_monitor: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "teleop_monitor: error: " << e.what() << "\n";
    return 1;
  }
}
