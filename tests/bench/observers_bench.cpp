// teleop_bench observers --out DIR [--quick] [--no-chart] [--counts 0,8,16,32] [--rounds 3]
//                        [--duration 10] [--full-rate-counts 32] [--domain 110] [--bin-dir DIR]
//
// Do observers load the loop? A real session per row: teleop_server (default scene) and
// teleop_master (simulated device, --duration S after homing) as separate processes on the
// loopback profile and a domain of its own, with N observers as separate processes started
// before the master and stopped after it. Half of them (rounded up) are real `teleop_monitor
// --json` processes, the other half `teleop_bench observer-probe --kind view`: a headless
// subscriber that reads exactly the topics teleop_viewer reads (common/dds/observer_topics.hpp),
// without drawing. Both use the observers' defaults (the rate-limited topics); the full-rate
// rows (--full-rate-counts, one session each, after the rounds) pass --full-rate to every
// observer, as earlier versions subscribed. Every observer runs at nice 19 (the viewer's and the
// monitor's default --nice); the rate_limited_nice0 rows (--nice0-counts) run the default
// topics at nice 0, to separate what the topics and what the priority each bring.
//
// The observer counts are interleaved within each round (0, 8, 16, 32, 0, 8, ...), so a change
// of the machine's load spreads over all of them. Per session: the master's round trip p50 /
// p99 / p99.9, overruns, link losses, commands sent / received and verdict; the server's
// watchdog trips during the session (the one trip when the master stops is not counted), step
// p99 and overruns; the 1-minute load average at the start; how many observers got the scene
// and their median slave_state rate.
//
// After the sweep: the cost of one observer (the slopes of the master's round-trip p99 and the
// server's step p99 over the count) and the smallest count at which the round-trip p99 is twice
// the 0-observer one, printed and written to DIR/observers_scaling.csv.
//
// Writes DIR/observers.csv and DIR/observers.png (tests/charts/observers.py).
#include <signal.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "common/config/config.hpp"
#include "common/dds/endpoint.hpp"
#include "common/dds/observer_topics.hpp"
#include "common/util/clock.hpp"
#include "common/util/csv.hpp"
#include "common/util/json.hpp"
#include "common/util/registry.hpp"
#include "common/util/signals.hpp"
#include "common/util/stats.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"
#include "tests/support/process.hpp"

namespace teleop::bench {
namespace {

namespace fs = std::filesystem;
using teleop::test::json_nested;
using teleop::test::json_text;
using teleop::test::json_value;
using teleop::test::Process;

std::string self_exe() {
  char self[4096];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
  if (n <= 0) throw std::runtime_error("cannot find /proc/self/exe");
  self[n] = '\0';
  return self;
}

// ---------------------------------------------------------------------------------------------
// observer-probe: what teleop_viewer subscribes to, without a window

int observer_probe(const CommandArgs& args) {
  const std::string kind_text = args.option("--kind", "view");
  if (kind_text != "view" && kind_text != "monitor") {
    throw config::ConfigError("--kind '" + kind_text + "': expected view or monitor");
  }
  const bool full_rate = args.option("--full-rate", "0") == "1";
  // the options' ranges were checked (the registration at the end of this file) before the run
  const int domain = std::stoi(args.option("--domain", "110"));
  const double duration_s = std::stod(args.option("--duration", "0"));
  // as teleop_viewer does by default (--nice 19), before any DDS thread starts
  const double nice = std::stod(args.option("--nice", "19"));
  if (nice > 0 && setpriority(PRIO_PROCESS, 0, static_cast<int>(nice)) != 0) {
    std::fprintf(stderr, "observer-probe: cannot lower the priority (--nice %.0f)\n", nice);
  }
  const dds::ObserverTopics t = dds::observer_topics(
      kind_text == "view" ? dds::ObserverKind::kView : dds::ObserverKind::kMonitor, full_rate);
  dds::Participant p(dds::ParticipantOptions{"loopback", domain, "observer-probe"});
  install_stop_signal_handlers();
  std::atomic<std::uint64_t> slave{0}, master{0}, frames{0}, commands{0}, scene{0}, stats{0};
  using Info = eprosima::fastdds::dds::SampleInfo;
  // the viewer copies each sample into its store; a copy here costs about the same
  SlaveState last_slave;
  MasterState last_master;
  MeshFrame last_frame;
  dds::Reader<SceneDescriptionPubSubType> r_scene(
      p, dds::topics::kScene, [&](const SceneDescription&, const Info&) { scene.fetch_add(1); });
  dds::Reader<MeshTopologyPubSubType> r_topology(p, dds::topics::kMeshTopology,
                                                 [&](const MeshTopology&, const Info&) {});
  dds::Reader<MeshFramePubSubType> r_frames(p, t.mesh_frame, [&](const MeshFrame& f, const Info&) {
    last_frame = f;
    frames.fetch_add(1);
  });
  dds::Reader<SlaveStatePubSubType> r_slave(p, t.slave_state,
                                            [&](const SlaveState& s, const Info&) {
                                              last_slave = s;
                                              slave.fetch_add(1);
                                            });
  dds::Reader<MasterStatePubSubType> r_master(p, t.master_state,
                                              [&](const MasterState& s, const Info&) {
                                                last_master = s;
                                                master.fetch_add(1);
                                              });
  dds::Reader<ServerStatsPubSubType> r_stats(
      p, dds::topics::kServerStats, [&](const ServerStats&, const Info&) { stats.fetch_add(1); });
  dds::Reader<EventPubSubType> r_events(p, dds::topics::kEvents, [&](const Event&, const Info&) {});
  std::unique_ptr<dds::Reader<MasterCommandPubSubType>> r_cmd;
  if (t.master_command) {
    r_cmd = std::make_unique<dds::Reader<MasterCommandPubSubType>>(
        p, dds::topics::kMasterCommand,
        [&](const MasterCommand&, const Info&) { commands.fetch_add(1); });
  }
  const auto t0 = now_ns();
  while (!stop_requested() && (duration_s <= 0 || seconds_between(t0, now_ns()) < duration_s)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  const double elapsed = seconds_between(t0, now_ns());
  const auto count = [](const std::atomic<std::uint64_t>& n) {
    return teleop::OrderedJson{{"count", n.load()}};
  };
  teleop::OrderedJson line;
  line["type"] = "probe";
  line["kind"] = kind_text;
  line["full_rate"] = full_rate;
  line["elapsed_s"] = std::round(elapsed * 1e3) / 1e3;
  line["topics"] = {{"slave_state", count(slave)},  {"master_state", count(master)},
                    {"mesh_frame", count(frames)},  {"master_command", count(commands)},
                    {"server_stats", count(stats)}, {"scene", count(scene)}};
  std::printf("%s\n", teleop::json_line(line).c_str());
  std::fflush(stdout);
  return 0;
}

// ---------------------------------------------------------------------------------------------
// observers: the sweep

struct Binaries {
  std::string server, master, monitor, self;
};

struct SessionResult {
  double load1 = 0;
  double rtt_p50 = NAN, rtt_p99 = NAN, rtt_p999 = NAN;
  double master_overruns = NAN, link_losses = NAN, sent = NAN, received = NAN;
  std::string verdict = "?";
  double watchdog_trips = NAN, server_step_p99_us = NAN, server_overruns = NAN;
  int observers_with_scene = 0;
  double monitor_state_hz = NAN;  ///< median over the monitors of their slave_state rate
  double view_state_hz = NAN;     ///< median over the view probes of their slave_state rate
  double server_steps = NAN, server_step_p50_us = NAN;
  double collision_p99_us = NAN, deformable_p99_us = NAN, slave_p99_us = NAN, publish_p99_us = NAN;
};

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

/// The count of `topic` in the last JSON object of an observer's output that has it.
double last_count(const std::string& out, const std::string& topic) {
  std::istringstream lines(out);
  double count = 0.0;
  for (std::string line; std::getline(lines, line);) {
    const double c = json_nested(line, topic, "count");
    if (!std::isnan(c)) count = c;
  }
  return count;
}

/// Whether an observer's output has a scene line ({"type": "scene", ...}).
bool has_scene_line(const std::string& out) {
  std::istringstream lines(out);
  for (std::string line; std::getline(lines, line);) {
    if (json_text(line, "type") == "scene") return true;
  }
  return false;
}

/// Scheduling flags given to the server's and the master's loops in a live session.
struct LoopFlags {
  std::string name = "normal";
  std::vector<std::string> server, master;
};

/// The observer processes of a session and when each started [s since the session's start].
struct Observers {
  std::vector<std::unique_ptr<Process>> procs;
  std::vector<double> started_s;
};

/// N observers: even ones `teleop_monitor --json`, odd ones a view probe (this program's
/// observer-probe), all at `nice`, with --full-rate when `full_rate`.
Observers start_observers(const Binaries& bin, int observers, bool full_rate, int nice,
                          const std::string& d, const fs::path& work, std::int64_t t0) {
  Observers obs;
  for (int i = 0; i < observers; ++i) {
    const bool monitor = i % 2 == 0;
    std::vector<std::string> a;
    if (monitor) {
      a = {"--domain", d, "--json", "--period", "1", "--nice", std::to_string(nice)};
      if (full_rate) a.push_back("--full-rate");
      obs.procs.push_back(
          std::make_unique<Process>(bin.monitor, a, "obs_bench_mon" + std::to_string(i)));
    } else {
      a = {"observer-probe",
           "--out",
           work.string(),
           "--kind",
           "view",
           "--domain",
           d,
           "--full-rate",
           full_rate ? "1" : "0",
           "--nice",
           std::to_string(nice)};
      obs.procs.push_back(
          std::make_unique<Process>(bin.self, a, "obs_bench_view" + std::to_string(i)));
    }
    obs.started_s.push_back(seconds_between(t0, now_ns()));
  }
  return obs;
}

/// Stops the observers (SIGINT, SIGKILL after 20 s) and reads from their output how many got
/// the scene and the median slave_state rate of the monitors and of the view probes.
void stop_observers(Observers& obs, double stopped_s, SessionResult& r) {
  for (auto& o : obs.procs) o->signal(SIGINT);
  std::vector<double> monitor_rates, view_rates;
  for (std::size_t i = 0; i < obs.procs.size(); ++i) {
    if (obs.procs[i]->wait_for(20.0) < 0) obs.procs[i]->signal(SIGKILL);
    const std::string out = obs.procs[i]->out();
    if (last_count(out, "scene") > 0 || has_scene_line(out)) {
      ++r.observers_with_scene;
    }
    const double alive = stopped_s - obs.started_s[i];
    if (alive > 0) {
      (i % 2 == 0 ? monitor_rates : view_rates).push_back(last_count(out, "slave_state") / alive);
    }
  }
  r.monitor_state_hz = median(monitor_rates);
  r.view_state_hz = median(view_rates);
}

/// The master's (`m`) and the server's (`s`) summary JSON into `r`.
void read_summaries(const std::string& m, const std::string& s, SessionResult& r) {
  r.rtt_p50 = json_nested(m, "rtt_ms", "p50");
  r.rtt_p99 = json_nested(m, "rtt_ms", "p99");
  r.rtt_p999 = json_nested(m, "rtt_ms", "p999");
  r.master_overruns = json_value(m, "overruns");  // the first "overruns" key is the loop's
  r.link_losses = json_value(m, "link_losses");
  r.sent = json_value(m, "sent");
  r.received = json_value(m, "received");
  if (const std::string v = json_text(m, "verdict"); !v.empty()) r.verdict = v;
  // the master's end stops the commands: the server's watchdog trips once then, by design
  const double trips = json_value(s, "watchdog_trips");
  r.watchdog_trips = std::isnan(trips) ? trips : std::max(0.0, trips - 1.0);
  r.server_step_p99_us = json_nested(s, "step_us", "p99");
  r.server_overruns = json_value(s, "overruns");
  r.server_steps = json_value(s, "steps");
  r.server_step_p50_us = json_nested(s, "step_us", "p50");
  const auto part_p99 = [&](const char* part) { return json_nested(s, part, "p99"); };
  r.collision_p99_us = part_p99("collision");
  r.deformable_p99_us = part_p99("deformable");
  r.slave_p99_us = part_p99("slave");
  r.publish_p99_us = part_p99("publish");
}

SessionResult run_session(const Binaries& bin, int observers, bool full_rate, int nice, int domain,
                          double duration_s, const fs::path& work,
                          const LoopFlags& loops = LoopFlags{}) {
  SessionResult r;
  double load[3] = {0, 0, 0};
  if (getloadavg(load, 3) > 0) r.load1 = load[0];
  const std::string d = std::to_string(domain);
  const std::string tag =
      std::to_string(observers) + (full_rate ? "f" : "r") + "n" + std::to_string(nice);
  const std::string server_json = (work / ("server_" + tag + ".json")).string();
  const std::string master_json = (work / ("master_" + tag + ".json")).string();
  fs::remove(server_json);
  fs::remove(master_json);
  std::vector<std::string> sargs = {"--domain", d, "--summary-json", server_json, "--quiet"};
  sargs.insert(sargs.end(), loops.server.begin(), loops.server.end());
  Process server(bin.server, sargs, "obs_bench_server");
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  const auto t0 = now_ns();
  Observers obs = start_observers(bin, observers, full_rate, nice, d, work, t0);
  // let every observer start and discover the others before the session starts: the steady
  // state is measured (32 participants starting at once on 2 cores take a few seconds of CPU)
  std::this_thread::sleep_for(std::chrono::milliseconds(2000 + 150 * observers));
  std::vector<std::string> margs = {
      "--domain",       d,           "--duration", std::to_string(duration_s),
      "--summary-json", master_json, "--quiet"};
  margs.insert(margs.end(), loops.master.begin(), loops.master.end());
  Process master(bin.master, margs, "obs_bench_master");
  const int mst = master.wait_for(duration_s + 60.0);
  stop_observers(obs, seconds_between(t0, now_ns()), r);
  server.signal(SIGTERM);
  server.wait_for(20.0);
  if (mst != 0) {
    std::fprintf(stderr, "observers: master exited with %d: %s\n", mst, master.err().c_str());
  }
  read_summaries(Process::slurp(master_json), Process::slurp(server_json), r);
  return r;
}

std::vector<int> parse_counts(const std::string& flag, const std::string& text) {
  std::vector<int> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (item.empty()) continue;
    char* end = nullptr;
    const long v = std::strtol(item.c_str(), &end, 10);
    if (*end != '\0' || v < 0 || v > 128) {
      throw config::ConfigError(flag + " '" + text + "': '" + item +
                                "' is not an observer count in [0, 128]");
    }
    out.push_back(static_cast<int>(v));
  }
  return out;
}

/// One --variants item: remedies joined by '+': normal, fifoP (SCHED_FIFO priority P), spinN
/// (busy-wait N us before each deadline), dmaN (hold /dev/cpu_dma_latency at N us), prewarmN
/// (the server reads the next step's data into the caches in the last N us before each
/// deadline), mlock (both lock their memory), niceN (both loops at nice N, e.g. nice-20), pin (the
/// server's loop on the last CPU, the master's on the one before).
LoopFlags parse_variant(const std::string& text) {
  LoopFlags f;
  f.name = text;
  std::stringstream ss(text);
  std::string item;
  const auto both = [&](const std::string& flag, const std::string& v) {
    f.server.insert(f.server.end(), {flag, v});
    f.master.insert(f.master.end(), {flag, v});
  };
  const auto number_after = [&](const std::string& word, std::size_t at) {
    const std::string digits = word.substr(at);
    if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos) {
      throw config::ConfigError("--variants '" + text + "': '" + word +
                                "' needs a non-negative integer after its name");
    }
    return digits;
  };
  while (std::getline(ss, item, '+')) {
    if (item == "normal") continue;
    if (item == "pin") {
      // the server's loop on the last CPU, the master's on the one before (one CPU: both on it)
      const unsigned cpus = std::max(1U, std::thread::hardware_concurrency());
      f.server.insert(f.server.end(), {"--cpu", std::to_string(cpus - 1)});
      f.master.insert(f.master.end(), {"--cpu", std::to_string(cpus >= 2 ? cpus - 2 : 0)});
    } else if (item.rfind("fifo", 0) == 0) {
      both("--realtime", number_after(item, 4));
    } else if (item.rfind("spin", 0) == 0) {
      both("--spin-us", number_after(item, 4));
    } else if (item.rfind("dma", 0) == 0) {
      both("--dma-latency-us", number_after(item, 3));
    } else if (item.rfind("prewarm", 0) == 0) {
      f.server.insert(f.server.end(), {"--prewarm-us", number_after(item, 7)});
    } else if (item.rfind("nice", 0) == 0) {
      const bool negative = item.size() > 4 && item[4] == '-';
      both("--nice", (negative ? "-" : "") + number_after(item, negative ? 5 : 4));
    } else if (item == "mlock") {
      f.server.push_back("--lock-memory");
      f.master.push_back("--lock-memory");
    } else {
      throw config::ConfigError(
          "--variants '" + text + "': '" + item +
          "' is not one of normal, fifoP, spinN, dmaN, prewarmN, mlock, niceN, pin");
    }
  }
  return f;
}

std::vector<LoopFlags> live_variants(const CommandArgs& args) {
  std::vector<LoopFlags> out;
  const std::string variants = args.option("--variants", "");
  if (variants.empty()) {
    for (const int p : parse_counts("--realtime", args.option("--realtime", "0,20"))) {
      out.push_back(parse_variant(p > 0 ? "fifo" + std::to_string(p) : "normal"));
    }
    return out;
  }
  std::stringstream ss(variants);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!item.empty()) out.push_back(parse_variant(item));
  }
  return out;
}

/// A live session: server, master and N observers, with the loops as normal threads or with
/// the remedies of --variants (or the priorities of --realtime); rounds interleave every
/// (variant, count) pair.
int live_bench(const CommandArgs& args, const Binaries& bin, const fs::path& work) {
  const std::vector<int> counts = parse_counts("--counts", args.option("--counts", "0,8"));
  std::vector<LoopFlags> variants = live_variants(args);
  const std::string scene = args.option("--scene", "");
  if (!scene.empty()) {
    for (LoopFlags& v : variants) v.server.insert(v.server.end(), {"--scene", scene});
  }
  // the options' ranges were checked (the registration at the end of this file) before the run
  const double rounds = std::stod(args.option("--rounds", args.quick ? "1" : "3"));
  const double duration_s = std::stod(args.option("--duration", args.quick ? "3" : "10"));
  const double domain = std::stod(args.option("--domain", "110"));
  const std::string csv_path = (args.out_dir / "live.csv").string();
  CsvWriter csv(csv_path,
                {"loops", "observers", "round", "load1", "server_steps", "server_overruns",
                 "server_overrun_percent", "server_step_us_p50", "server_step_us_p99",
                 "collision_us_p99", "deformable_us_p99", "slave_us_p99", "publish_us_p99",
                 "rtt_ms_p99", "master_overruns", "link_losses", "watchdog_trips", "verdict"});
  Progress progress("observers live",
                    static_cast<int>(rounds) * static_cast<double>(variants.size() * counts.size()),
                    "sessions");
  for (int round = 1; round <= static_cast<int>(rounds); ++round) {
    for (const LoopFlags& loops : variants) {
      for (const int n : counts) {
        const SessionResult r =
            run_session(bin, n, false, 19, static_cast<int>(domain), duration_s, work, loops);
        const double pct = 100.0 * r.server_overruns / r.server_steps;
        csv.row_text({loops.name, std::to_string(n), std::to_string(round), format_number(r.load1),
                      format_number(r.server_steps), format_number(r.server_overruns),
                      format_number(pct), format_number(r.server_step_p50_us),
                      format_number(r.server_step_p99_us), format_number(r.collision_p99_us),
                      format_number(r.deformable_p99_us), format_number(r.slave_p99_us),
                      format_number(r.publish_p99_us), format_number(r.rtt_p99),
                      format_number(r.master_overruns), format_number(r.link_losses),
                      format_number(r.watchdog_trips), r.verdict});
        csv.flush();
        std::printf(
            "live %-12s %2d observers round %d load %.2f: server step p50 %.1f p99 %.1f "
            "us, overruns %.0f of %.0f (%.3f %%), parts p99 collision %.1f deformable "
            "%.1f slave %.1f publish %.1f us; master rtt p99 %.3f ms overruns %.0f; link losses "
            "%.0f, watchdog trips %.0f; verdict %s\n",
            loops.name.c_str(), n, round, r.load1, r.server_step_p50_us, r.server_step_p99_us,
            r.server_overruns, r.server_steps, pct, r.collision_p99_us, r.deformable_p99_us,
            r.slave_p99_us, r.publish_p99_us, r.rtt_p99, r.master_overruns, r.link_losses,
            r.watchdog_trips, r.verdict.c_str());
        std::fflush(stdout);
        progress.add();
      }
    }
  }
  progress.finish();
  return 0;
}

/// Least-squares slope of y over x (NAN with fewer than two distinct x).
double slope(const std::vector<double>& x, const std::vector<double>& y) {
  if (x.size() < 2) return NAN;
  double mx = 0, my = 0;
  for (std::size_t i = 0; i < x.size(); ++i) mx += x[i], my += y[i];
  mx /= static_cast<double>(x.size());
  my /= static_cast<double>(y.size());
  double sxy = 0, sxx = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
  }
  return sxx > 0 ? sxy / sxx : std::numeric_limits<double>::quiet_NaN();
}

/// The cost of one observer: per observer count, the medians over the rounds of the master's
/// round-trip p99 and the server's step p99; the least-squares slopes of both over the count;
/// and the smallest count whose round-trip p99 is at least twice the 0-observer one (the limit
/// where the loop's p99 doubles). Printed and written to `csv_path`.
void report_scaling(const std::map<int, std::vector<SessionResult>>& by_count,
                    const std::string& csv_path) {
  CsvWriter csv(csv_path, {"observers", "sessions", "rtt_ms_p99_median",
                           "server_step_us_p99_median", "server_overruns_median", "ratio_to_0"});
  std::vector<double> xs, rtts, steps;
  double base = NAN;
  int doubled_at = -1;
  for (const auto& [n, rows] : by_count) {
    std::vector<double> rtt, step, over;
    for (const SessionResult& r : rows) {
      rtt.push_back(r.rtt_p99);
      step.push_back(r.server_step_p99_us);
      over.push_back(r.server_overruns);
    }
    const double m_rtt = median(rtt), m_step = median(step);
    if (n == 0) base = m_rtt;
    const double ratio = m_rtt / base;
    if (doubled_at < 0 && n > 0 && ratio >= 2.0) doubled_at = n;
    if (std::isfinite(m_rtt) && std::isfinite(m_step)) {
      xs.push_back(n);
      rtts.push_back(m_rtt);
      steps.push_back(m_step);
    }
    csv.row_text({std::to_string(n), std::to_string(rows.size()), format_number(m_rtt),
                  format_number(m_step), format_number(median(over)), format_number(ratio)});
  }
  csv.flush();
  const int largest = by_count.empty() ? 0 : by_count.rbegin()->first;
  std::printf(
      "observers: cost per observer (least squares over the counts, medians over the rounds): "
      "round trip p99 %+.4f ms, server step p99 %+.2f us; the round trip p99 doubles (against "
      "%.3f ms with none) at %s\n",
      slope(xs, rtts), slope(xs, steps), base,
      doubled_at > 0 ? (std::to_string(doubled_at) + " observers").c_str()
                     : ("no count up to " + std::to_string(largest)).c_str());
  std::fflush(stdout);
}

int observers_bench(const CommandArgs& args) {
  const std::vector<int> counts =
      parse_counts("--counts", args.option("--counts", args.quick ? "0,2" : "0,8,16,32"));
  const std::vector<int> full_counts =
      parse_counts("--full-rate-counts", args.option("--full-rate-counts", args.quick ? "" : "32"));
  const std::vector<int> nice0_counts =
      parse_counts("--nice0-counts", args.option("--nice0-counts", args.quick ? "" : "32"));
  // the options' ranges were checked (the registration at the end of this file) before the run
  const double rounds = std::stod(args.option("--rounds", args.quick ? "1" : "3"));
  const double duration_s = std::stod(args.option("--duration", args.quick ? "3" : "10"));
  const double domain = std::stod(args.option("--domain", "110"));
  const fs::path self = self_exe();
  const fs::path build =
      fs::path(args.option("--bin-dir", self.parent_path().parent_path().parent_path().string()));
  const Binaries bin{(build / "server/teleop_server").string(),
                     (build / "client/teleop_master").string(),
                     (build / "client/teleop_monitor").string(), self.string()};
  for (const std::string& b : {bin.server, bin.master, bin.monitor}) {
    if (!fs::exists(b)) {
      throw config::ConfigError("--bin-dir '" + build.string() + "': " + b +
                                " does not exist (build teleop_server, teleop_master and "
                                "teleop_monitor)");
    }
  }
  const fs::path work = args.out_dir / "observers_work";
  fs::create_directories(work);
  if (args.option("--live", "0") == "1") return live_bench(args, bin, work);
  const std::string csv_path = (args.out_dir / "observers.csv").string();
  CsvWriter csv(csv_path,
                {"mode", "observers", "round", "load1", "rtt_ms_p50", "rtt_ms_p99", "rtt_ms_p999",
                 "master_overruns", "link_losses", "commands_sent", "commands_received", "verdict",
                 "server_watchdog_trips", "server_step_us_p99", "server_overruns",
                 "observers_with_scene", "monitor_state_hz", "view_state_hz"});
  Progress progress("observers",
                    static_cast<int>(rounds) * static_cast<double>(counts.size()) +
                        static_cast<double>(full_counts.size() + nice0_counts.size()),
                    "sessions");
  std::map<int, std::vector<SessionResult>> by_count;  // the rate-limited rows
  auto run = [&](const char* mode, int n, int round) {
    const std::string m = mode;
    const SessionResult r =
        run_session(bin, n, m == "full_rate", m == "rate_limited_nice0" ? 0 : 19,
                    static_cast<int>(domain), duration_s, work);
    if (m == "rate_limited") by_count[n].push_back(r);
    csv.row_text({mode, std::to_string(n), std::to_string(round), format_number(r.load1),
                  format_number(r.rtt_p50), format_number(r.rtt_p99), format_number(r.rtt_p999),
                  format_number(r.master_overruns), format_number(r.link_losses),
                  format_number(r.sent), format_number(r.received), r.verdict,
                  format_number(r.watchdog_trips), format_number(r.server_step_p99_us),
                  format_number(r.server_overruns), std::to_string(r.observers_with_scene),
                  format_number(r.monitor_state_hz), format_number(r.view_state_hz)});
    csv.flush();
    std::printf(
        "%-12s %3d observers round %d  load %.2f  rtt p50 %.3f p99 %.3f ms  master overruns "
        "%.0f  link losses %.0f  received %.0f/%.0f  %s  watchdog %.0f  server step p99 %.1f "
        "us overruns %.0f  scene %d/%d  state at monitors %.1f Hz, views %.1f Hz\n",
        mode, n, round, r.load1, r.rtt_p50, r.rtt_p99, r.master_overruns, r.link_losses, r.received,
        r.sent, r.verdict.c_str(), r.watchdog_trips, r.server_step_p99_us, r.server_overruns,
        r.observers_with_scene, n, r.monitor_state_hz, r.view_state_hz);
    std::fflush(stdout);
    progress.add();
  };
  for (int round = 1; round <= static_cast<int>(rounds); ++round) {
    for (const int n : counts) run("rate_limited", n, round);
  }
  for (const int n : full_counts) run("full_rate", n, 1);
  for (const int n : nice0_counts) run("rate_limited_nice0", n, 1);
  progress.finish();
  csv.flush();
  report_scaling(by_count, (args.out_dir / "observers_scaling.csv").string());
  if (!args.no_chart) {
    run_chart_script("observers.py", {csv_path, (args.out_dir / "observers.png").string()});
  }
  return 0;
}

TELEOP_REGISTER_COMMAND(
    bench, "observers",
    "server + master with 0-32 observer processes: round trip, overruns, "
    "link losses, watchdog trips",
    observers_bench, text_option("--counts", "observer counts N,N,..."),
    text_option("--full-rate-counts", "counts with --full-rate observers"),
    text_option("--nice0-counts", "counts with observers at nice 0"),
    text_option("--realtime", "priorities P,P,... (live)"),
    text_option("--scene", "the server's scene (live; default: default.yaml)"),
    text_option("--variants",
                "loop remedies V,V,... (live): normal, fifoP, spinN, dmaN, prewarmN, mlock, niceN, "
                "pin, joined by +"),
    integer_option("--rounds", 1, 100, "rounds"),
    number_option("--duration", 1, 600, "session length [s]"),
    integer_option("--domain", 0, 232, "DDS domain id"),
    text_option("--bin-dir", "build folder of the executables"),
    integer_option("--live", 0, 1, "1: the live session benchmark"));
TELEOP_REGISTER_COMMAND(bench, "observer-probe",
                        "(internal) a headless observer reading what teleop_viewer reads",
                        observer_probe, text_option("--kind", "view | monitor"),
                        integer_option("--full-rate", 0, 1, "1: the 1 kHz topics"),
                        integer_option("--domain", 0, 232, "DDS domain id"),
                        number_option("--duration", 0, 1e6, "stop after [s], 0 = never"),
                        number_option("--nice", 0, 19, "nice value"));

}  // namespace
}  // namespace teleop::bench
