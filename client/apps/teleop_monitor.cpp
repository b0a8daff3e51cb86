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

#include <atomic>
#include <cstdio>
#include <deque>
#include <iostream>
#include <mutex>
#include <optional>
#include <thread>

#include "client/monitor/monitor_state.hpp"
#include "common/config/config.hpp"
#include "common/dds/endpoint.hpp"
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

int main(int argc, char** argv) {
  CLI::App app{"teleop_monitor: terminal observer of a teleoperation session"};
  std::optional<int> domain;
  std::optional<std::string> profile;
  std::optional<double> period_flag;
  double duration_s = 0.0;
  double stale_s = 0.5;
  bool json = false, lines = false, tui = false;
  bool full_rate = false;
  int nice = 19;
  app.add_option("--domain", domain, "DDS domain id, 0-232 (default: $TELEOP_DOMAIN or 0)");
  app.add_option("--profile", profile, "Fast DDS profile (default: loopback)");
  teleop::dds::NetworkFlags net_flags;
  teleop::dds::add_network_flags(app, net_flags);
  app.add_option("--period", period_flag,
                 "refresh / print period [s], 0.05-60 (default: 0.25 on the screen, 1 otherwise)");
  app.add_option("--duration", duration_s, "stop after this long [s], 0-1e7; 0 = until q/SIGINT");
  app.add_option("--stale", stale_s,
                 "a stream topic silent this long is STALE [s], 0.05-3600 (server_stats: at "
                 "least 3 s)")
      ->capture_default_str();
  auto* json_opt = app.add_flag("--json", json, "one JSON object per line, for scripts");
  auto* lines_opt = app.add_flag("--lines", lines, "scrolling text log (default off a terminal)");
  auto* tui_opt = app.add_flag("--tui", tui, "screen refreshed in place (default on a terminal)");
  app.add_flag("--full-rate", full_rate,
               "read the full-rate topics (slave_state 1 kHz, master_command, master_state, "
               "mesh_frame) instead of the 10 Hz *_monitor copies; loads the loops");
  app.add_option("--nice", nice,
                 "scheduling niceness of the monitor, 0-19: it yields the CPU to the server and "
                 "master on the same machine")
      ->capture_default_str();
  json_opt->excludes(lines_opt)->excludes(tui_opt);
  lines_opt->excludes(tui_opt);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "teleop_monitor: " << e.what() << "\n\n" << app.help();
    return 2;
  }
  try {
    using namespace teleop;
    const Mode mode = json    ? Mode::kJson
                      : lines ? Mode::kLines
                      : tui   ? Mode::kTui
                              : (isatty(STDOUT_FILENO) ? Mode::kTui : Mode::kLines);
    double period_s = period_flag ? *period_flag : (mode == Mode::kTui ? 0.25 : 1.0);
    config::check_flag("--period", period_s, 0.05, 60.0);
    config::check_flag("--duration", duration_s, 0.0, 1e7);
    config::check_flag("--stale", stale_s, 0.05, 3600.0);
    config::check_flag("--nice", nice, 0, 19);
    // before the participant: every DDS thread inherits the priority
    if (nice > 0 && setpriority(PRIO_PROCESS, 0, nice) != 0) {
      std::cerr << "teleop_monitor: warning: cannot lower the priority (--nice " << nice << ")\n";
    }
    const auto opts =
        teleop::dds::resolve_participant_options(profile, domain, "teleop_monitor", net_flags);
    teleop::dds::profile_file(opts.profile);
    teleop::dds::Participant p(opts);
    install_stop_signal_handlers();
    // a closed terminal (or tmux kill-server) ends the monitor cleanly too
    struct sigaction hup {};
    hup.sa_handler = [](int) { request_stop(); };
    sigemptyset(&hup.sa_mask);
    sigaction(SIGHUP, &hup, nullptr);

    const auto t0 = now_ns();
    std::mutex m;  // guards snap's values, events and stdout
    Snapshot snap;
    snap.domain = opts.domain;
    snap.profile = opts.profile;
    snap.full_rate = full_rate;
    const teleop::dds::ObserverTopics topics =
        teleop::dds::observer_topics(teleop::dds::ObserverKind::kMonitor, full_rate);
    struct TopicDef {
      const char* name;
      bool latched;
      double stale;
    };
    const std::vector<TopicDef> defs = {
        {"slave_state", false, stale_s},
        {"master_command", false, stale_s},
        {"master_state", false, stale_s},
        {"mesh_frame", false, stale_s},
        {"server_stats", false, std::max(stale_s, 3.0)},
        {"events", true, 0.0},
        {"scene", true, 0.0},
        {"mesh_topology", true, 0.0},
    };
    std::deque<Counter> counters(defs.size());
    auto counter = [&](const char* n) -> Counter& {
      for (std::size_t i = 0; i < defs.size(); ++i) {
        if (std::string(defs[i].name) == n) return counters[i];
      }
      return counters[0];
    };
    auto print_now = [&](const std::string& text) {  // lines and json modes only
      std::fputs(text.c_str(), stdout);
      std::fputc('\n', stdout);
      std::fflush(stdout);
    };

    namespace tdds = teleop::dds;
    using Info = eprosima::fastdds::dds::SampleInfo;
    // without --full-rate, master_command's row is the server's count of commands received
    bool have_commands_base = false;
    std::uint64_t commands_seen = 0;
    tdds::Reader<SlaveStatePubSubType> r_slave(
        p, topics.slave_state.name, topics.slave_state.qos, [&](const SlaveState& s, const Info&) {
          std::lock_guard<std::mutex> l(m);
          snap.slave = s;
          snap.have_slave = true;
          counter("slave_state").hit();
          if (topics.master_command) return;
          const std::uint64_t c = s.commands_received();
          if (!have_commands_base || c < commands_seen) {  // first sample, or a new server
            have_commands_base = true;
            commands_seen = c;
            return;
          }
          if (c > commands_seen) {
            Counter& cmd = counter("master_command");
            cmd.last_ns.store(teleop::now_ns());
            cmd.count.fetch_add(c - commands_seen);
            commands_seen = c;
          }
        });
    std::optional<tdds::Reader<MasterCommandPubSubType>> r_cmd;
    if (topics.master_command) {
      r_cmd.emplace(p, tdds::topics::kMasterCommand, tdds::TopicQos::kStream,
                    [&](const MasterCommand&, const Info&) { counter("master_command").hit(); });
    }
    tdds::Reader<MasterStatePubSubType> r_master(p, topics.master_state.name,
                                                 topics.master_state.qos,
                                                 [&](const MasterState& s, const Info&) {
                                                   std::lock_guard<std::mutex> l(m);
                                                   snap.master = s;
                                                   snap.have_master = true;
                                                   counter("master_state").hit();
                                                 });
    tdds::Reader<ServerStatsPubSubType> r_stats(p, tdds::topics::kServerStats,
                                                tdds::TopicQos::kReliableStream,
                                                [&](const ServerStats& s, const Info&) {
                                                  std::lock_guard<std::mutex> l(m);
                                                  snap.stats = s;
                                                  snap.have_stats = true;
                                                  counter("server_stats").hit();
                                                });
    tdds::Reader<SceneDescriptionPubSubType> r_scene(p, tdds::topics::kScene,
                                                     tdds::TopicQos::kLatched,
                                                     [&](const SceneDescription& s, const Info&) {
                                                       std::lock_guard<std::mutex> l(m);
                                                       snap.scene = s;
                                                       snap.have_scene = true;
                                                       counter("scene").hit();
                                                       if (mode == Mode::kLines)
                                                         print_now(monitor::scene_line(s));
                                                       if (mode == Mode::kJson)
                                                         print_now(monitor::scene_json(s));
                                                     });
    tdds::Reader<MeshTopologyPubSubType> r_topology(
        p, tdds::topics::kMeshTopology, tdds::TopicQos::kLatched,
        [&](const MeshTopology&, const Info&) { counter("mesh_topology").hit(); });
    tdds::Reader<MeshFramePubSubType> r_frames(
        p, topics.mesh_frame.name, topics.mesh_frame.qos,
        [&](const MeshFrame&, const Info&) { counter("mesh_frame").hit(); });
    tdds::Reader<EventPubSubType> r_events(
        p, tdds::topics::kEvents, tdds::TopicQos::kEventLog, [&](const Event& e, const Info&) {
          std::lock_guard<std::mutex> l(m);
          counter("events").hit();
          monitor::EventView ev{seconds_between(t0, now_ns()), e};
          snap.events.push_back(ev);
          while (snap.events.size() > 200) snap.events.pop_front();
          if (mode == Mode::kLines) print_now(monitor::event_line(ev));
          if (mode == Mode::kJson) print_now(monitor::event_json(ev));
        });

    RawKeys keys;
    if (mode == Mode::kTui) {
      std::fputs("\x1b[?1049h\x1b[?25l", stdout);  // alternate screen, hide the cursor
      std::fflush(stdout);
    }
    // rate over the last second: counts at past refreshes
    std::deque<std::pair<std::int64_t, std::vector<std::uint64_t>>> history;
    auto next = t0;
    while (!stop_requested()) {
      next += static_cast<std::int64_t>(period_s * 1e9);
      while (!stop_requested() && now_ns() < next) {
        if (keys.quit_pressed()) request_stop();
        // the screen polls the keyboard; the other modes only wait for the next period
        const std::int64_t step_ns = mode == Mode::kTui ? 20'000'000 : 100'000'000;
        std::this_thread::sleep_for(std::chrono::nanoseconds(
            std::max<std::int64_t>(0, std::min(step_ns, next - now_ns()))));
      }
      if (stop_requested()) break;
      const auto now = now_ns();
      std::vector<std::uint64_t> counts(defs.size());
      for (std::size_t i = 0; i < defs.size(); ++i) counts[i] = counters[i].count.load();
      history.emplace_back(now, counts);
      while (history.size() > 2 && seconds_between(history[1].first, now) >= 1.0) {
        history.pop_front();
      }
      const double window = seconds_between(history.front().first, now);
      std::lock_guard<std::mutex> l(m);
      snap.t_s = seconds_between(t0, now);
      snap.topics.clear();
      for (std::size_t i = 0; i < defs.size(); ++i) {
        TopicView t;
        t.name = defs[i].name;
        t.latched = defs[i].latched;
        t.stale_after_s = defs[i].stale;
        t.count = counts[i];
        t.rate_hz = window > 0.0
                        ? static_cast<double>(counts[i] - history.front().second[i]) / window
                        : 0.0;
        const auto last = counters[i].last_ns.load();
        t.age_s = t.count > 0 ? seconds_between(last, now) : -1.0;
        snap.topics.push_back(t);
      }
      if (mode == Mode::kJson) {
        print_now(monitor::render_json(snap));
      } else if (mode == Mode::kLines) {
        std::fputs(monitor::render_lines(snap).c_str(), stdout);
        std::fflush(stdout);
      } else {
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
      if (duration_s > 0 && snap.t_s >= duration_s) break;
    }
    if (mode == Mode::kTui) {
      std::fputs("\x1b[?25h\x1b[?1049l", stdout);  // restore the screen and the cursor
      std::fflush(stdout);
    }
    return 0;
  } catch (const teleop::config::ConfigError& e) {
    std::cerr << "teleop_monitor: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "teleop_monitor: error: " << e.what() << "\n";
    return 1;
  }
}
