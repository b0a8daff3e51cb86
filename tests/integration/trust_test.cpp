// What the network may decide for the operator (docs/topics.md, "A master is bound to its
// server"; docs/networking.md, "The haptic loop never waits on the network"):
//
//   - a rogue participant on the master's domain writes forged SlaveState (a 1e6 N contact
//     force, naming the master's own session as owner), forged ServerStats (huge fault counts)
//     and forged server fault events during a session: the force the master renders, its verdict
//     and the server's fault count in its summary are those of the same session without the
//     rogue, and every forged sample is counted;
//   - over TCP (wan_tcp profiles, in network namespaces the test makes itself), the master's
//     link is cut for a second: the haptic loop keeps its period, the cut is detected and the
//     force changes no faster than the device's rate bound. Skipped, with the reason, where
//     namespaces cannot be made.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <functional>
#include <sstream>
#include <thread>

#include "common/dds/endpoint.hpp"
#include "common/dds/teleop_idl.hpp"
#include "common/sim/events.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"
#include "tests/support/domains.hpp"
#include "tests/support/integration.hpp"
#include "tests/support/netns.hpp"
#include "tests/support/process.hpp"

namespace teleop::test {
namespace {

std::string tmp(const std::string& name) { return temp_path("trust", name); }

/// From a master --log: largest rendered force, largest change between cycles (overall, and
/// from `after_s` on between cycles either of which had the link lost), longest gap between cycles,
/// first cycle with the link lost at or after `after_s`, rows.
struct Trace {
  double peak_n = 0.0, max_step_n = 0.0, window_step_n = 0.0, max_gap_s = 0.0, first_lost_s = -1.0;
  /// the longest gap between log rows from 0.5 s before after_s to 2 s after it (the cut)
  double cut_gap_s = 0.0;
  std::size_t rows = 0;
};

Trace read_trace(const std::string& log, double after_s = 1e300) {
  std::istringstream in(Process::slurp(log));
  std::string line;
  Trace t;
  if (!std::getline(in, line)) return t;
  std::vector<std::string> names = split_csv_line(line);
  auto col = [&](const std::string& n) {
    for (std::size_t i = 0; i < names.size(); ++i) {
      if (names[i] == n) return static_cast<int>(i);
    }
    return -1;
  };
  const int it = col("t_s"), ix = col("fm_x"), il = col("link_ok");
  if (it < 0 || ix < 0 || il < 0) return t;
  double pt = 0, px = 0, py = 0, pz = 0;
  bool plost = false;
  while (std::getline(in, line)) {
    const std::vector<std::string> f = split_csv_line(line);
    if (f.size() < names.size()) continue;
    auto v = [&](int i) { return std::strtod(f[static_cast<std::size_t>(i)].c_str(), nullptr); };
    const double time = v(it), x = v(ix), y = v(ix + 1), z = v(ix + 2);
    t.peak_n = std::max(t.peak_n, std::sqrt(x * x + y * y + z * z));
    if (t.rows > 0) {
      const double step =
          std::sqrt((x - px) * (x - px) + (y - py) * (y - py) + (z - pz) * (z - pz));
      t.max_step_n = std::max(t.max_step_n, step);
      if (time >= after_s && (v(il) == 0.0 || plost)) {
        t.window_step_n = std::max(t.window_step_n, step);
      }
      t.max_gap_s = std::max(t.max_gap_s, time - pt);
      if (time >= after_s - 0.5 && pt <= after_s + 2.0)
        t.cut_gap_s = std::max(t.cut_gap_s, time - pt);
    }
    if (t.first_lost_s < 0 && time >= after_s && v(il) == 0.0) t.first_lost_s = time;
    pt = time, px = x, py = y, pz = z;
    plost = v(il) == 0.0;
    ++t.rows;
  }
  return t;
}

/// The text of "key": "value" in a JSON text ("" if absent).
std::string json_text(const std::string& json, const std::string& key) {
  const std::string needle = "\"" + key + "\": \"";
  const auto pos = json.find(needle);
  if (pos == std::string::npos) return "";
  const auto start = pos + needle.size();
  return json.substr(start, json.find('"', start) - start);
}

struct SessionRun {
  std::string master_json, master_err;
  Trace trace;
  int master_rc = -1;
};

/// A server on the default scene and a 5 s press-slip master session; `during` runs meanwhile.
SessionRun session(int domain, const std::string& name, const std::function<void()>& during = {}) {
  const std::string d = std::to_string(domain);
  const std::string mj = tmp(name + "_master.json"), log = tmp(name + "_master_log.csv");
  std::remove(mj.c_str());
  Process server(
      kServerBinary,
      {"--domain", d, "--duration", "60", "--scene", scene_file("default.yaml"), "--quiet"},
      name + "_server");
  Process master(kMasterBinary,
                 {"--domain", d, "--duration", "5", "--homing", "0.5", "--log", log,
                  "--summary-json", mj, "--quiet"},
                 name + "_master");
  if (during) during();
  SessionRun r;
  r.master_rc = master.wait_for(90.0);
  r.master_err = master.err();
  server.signal(SIGTERM);
  server.wait_for(20.0);
  r.master_json = Process::slurp(mj);
  r.trace = read_trace(log);
  std::printf("[ %-8s ] force peak %.3f N, largest change %.4f N per cycle, verdict %s\n",
              name.c_str(), r.trace.peak_n, r.trace.max_step_n,
              json_text(r.master_json, "verdict").c_str());
  return r;
}

/// Forged samples a rogue participant wrote.
struct Forged {
  std::atomic<int> states{0}, stats{0}, events{0};
};

/// The rogue: learns the master's session from its commands, then for 2.5 s writes forged
/// SlaveState at 1 kHz (1e6 N contact force, the master's session as the active owner, a step
/// counter that goes back now and then), forged ServerStats and forged server fault events.
void rogue(int domain, Forged& forged) {
  dds::Participant p(dds::ParticipantOptions{"loopback", domain, "rogue"});
  std::atomic<std::uint32_t> session{0};
  dds::Reader<MasterCommandPubSubType> commands(
      p, dds::topics::kMasterCommand,
      [&](const MasterCommand& c, const eprosima::fastdds::dds::SampleInfo&) {
        session.store(c.master_session());
      });
  dds::Writer<SlaveStatePubSubType> states(p, dds::topics::kSlaveState);
  dds::Writer<ServerStatsPubSubType> stats(p, dds::topics::kServerStats);
  dds::Writer<EventPubSubType> events(p, dds::topics::kEvents);
  // into the session: the master pressing the sphere
  std::this_thread::sleep_for(std::chrono::milliseconds(2500));
  SlaveState s;
  s.tip_orientation_wxyz()[0] = 1.0;
  s.contact_force_n()[2] = 1e6;
  s.in_contact(true);
  s.penetration_m(0.01);
  s.owner_session(session.load());
  s.owner_active(true);
  s.owner_first_seq(1);
  ServerStats st;
  Event e;
  for (int k = 0; k < 2500; ++k) {
    s.seq(static_cast<std::uint64_t>(k % 500));  // goes back: a forged "server restart"
    s.command_seq(static_cast<std::uint64_t>(1'000'000 + k));
    s.owner_commands_received(static_cast<std::uint64_t>(k));
    if (states.write(s)) ++forged.states;
    if (k % 100 == 0) {
      st.steps(static_cast<std::uint64_t>(k));
      st.faults(1'000'000 + static_cast<std::uint64_t>(k));
      st.watchdog_trips(1'000'000);
      st.overruns(1'000'000);
      if (stats.write(st)) ++forged.stats;
      e.seq(static_cast<std::uint64_t>(k));
      e.source("server");
      e.kind(static_cast<std::uint8_t>(sim::EventKind::kFault));
      e.severity(2);
      e.message("forged fault");
      if (events.write(e)) ++forged.events;
    }
    std::this_thread::sleep_for(std::chrono::microseconds(1000));
  }
}

TEST(Trust, ARogueParticipantChangesNothingTheOperatorFeelsOrTheSummarySays) {
  const SessionRun base = session(domains::kRogueBaseline, "baseline");
  Forged forged;
  const SessionRun r = session(domains::kRogueParticipant, "rogue",
                               [&] { rogue(domains::kRogueParticipant, forged); });
  std::printf("[ rogue    ] forged %d states, %d stats, %d events; master: %s\n",
              forged.states.load(), forged.stats.load(), forged.events.load(),
              r.master_json.substr(r.master_json.find("\"server_binding\""), 220).c_str());
  ASSERT_EQ(base.master_rc, 0) << base.master_err;
  ASSERT_EQ(r.master_rc, 0) << r.master_err;
  ASSERT_GT(forged.states.load(), 1000);
  const std::string& m = r.master_json;
  // what the operator feels: the same force as without the rogue (generous: runs differ)
  EXPECT_GT(r.trace.rows, 4000u);
  EXPECT_LT(r.trace.peak_n, 10.0);
  EXPECT_NEAR(r.trace.peak_n, base.trace.peak_n, std::max(0.5, 0.3 * base.trace.peak_n));
  EXPECT_LE(r.trace.max_step_n, std::max(0.1, 2.0 * base.trace.max_step_n));
  EXPECT_LT(json_nested(m, "metrics", "mean_contact_force_n"), 100.0) << m;
  // what the summary says: the verdict and the server's counts of the real server
  EXPECT_EQ(json_text(m, "verdict"), json_text(base.master_json, "verdict")) << m;
  EXPECT_EQ(json_nested(m, "server", "faults"), json_nested(base.master_json, "server", "faults"));
  EXPECT_EQ(json_nested(m, "server", "watchdog_trips"), 0.0) << m;
  EXPECT_EQ(json_nested(m, "server", "restarts"), 0.0) << m;
  EXPECT_EQ(json_nested(m, "rehomes", "slave_restart"), 0.0) << m;
  // the forged samples were counted (generous: best-effort samples may be lost on the way)
  EXPECT_GE(json_nested(m, "foreign", "states"), 0.5 * forged.states.load()) << m;
  EXPECT_GE(json_nested(m, "foreign", "stats"), 1.0) << m;
  EXPECT_GE(json_nested(m, "foreign", "events"), 1.0) << m;
  EXPECT_NE(m.find("\"bound\": true"), std::string::npos) << m;
  EXPECT_EQ(json_nested(base.master_json, "foreign", "states"), 0.0) << base.master_json;
}

/// `exe` with `args` run on host `host` of the lab.
std::unique_ptr<Process> on_host(NetnsLab& lab, int host, const std::string& exe,
                                 const std::vector<std::string>& args, const std::string& tag) {
  std::vector<std::string> argv = lab.exec_prefix(host);
  argv.push_back(exe);
  argv.insert(argv.end(), args.begin(), args.end());
  return std::make_unique<Process>(lab.ip(), argv, "trust_" + tag);
}

/// The session time in the master's `log` 2 s after its first live cycle (phase 1), looked
/// for over 30 s; -1 when the session never started.
double two_seconds_into_the_session(const std::string& log) {
  double cut_at_s = -1.0;
  for (int k = 0; k < 300 && cut_at_s < 0; ++k) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    const std::vector<std::vector<double>> cols =
        csv_columns(Process::slurp(log), {"t_s", "phase"});
    if (cols.size() == 2 && !cols[1].empty() && cols[1].back() == 1.0) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2000));
      const auto now = csv_columns(Process::slurp(log), {"t_s"});
      cut_at_s = now.empty() || now[0].empty() ? 0.0 : now[0].back();
    }
  }
  return cut_at_s;
}

/// The master's port leaves the bridge for 1 s (its packets vanish silently, as on a broken
/// path).
void cut_master_link_for_a_second(NetnsLab& lab) {
  const std::string port = "-n " + lab.switch_ns() + " link set p2 ";
  ASSERT_EQ(std::system((lab.ip() + " " + port + "nomaster").c_str()), 0);
  std::this_thread::sleep_for(std::chrono::milliseconds(1000));
  ASSERT_EQ(std::system((lab.ip() + " " + port + "master br0").c_str()), 0);
}

/// Through the cut at `cut_at_s` the loop kept its period, saw the link lost and faded the
/// force within its rate bound (`m`: the master's summary, `log`: its log).
void expect_period_kept_through_the_cut(const std::string& m, const std::string& log,
                                        double cut_at_s) {
  const Trace t = read_trace(log, cut_at_s);
  const double rate_bound = json_nested(m, "safety", "max_force_rate_n_per_s");
  const double rate_hz = json_value(m, "rate_hz");
  std::printf(
      "trust_test TcpLinkCut: longest cycle gap %.1f ms, link lost %.0f ms after the cut, "
      "largest force change %.4f N per cycle (%.4f N with the link lost; bound %.0f N/s), %s "
      "issued "
      "in %.2f s\n",
      t.max_gap_s * 1e3, (t.first_lost_s - cut_at_s) * 1e3, t.max_step_n, t.window_step_n,
      rate_bound, std::to_string(json_value(m, "issued")).c_str(), json_value(m, "duration_s"));
  // the loop kept its period through the cut (generous for a loaded 2-core machine: the loop
  // that waited on TCP froze for the whole cut and more)
  // through the cut (0.5 s before it to 1 s after the link is back) the loop kept its period;
  // over the whole session no gap comes near the cut's length (the loop that waited on TCP froze
  // for 1.5-1.9 s): a 0.3 s stall of a loaded CI machine running other tests beside this one
  // was seen outside the cut
  EXPECT_LT(t.cut_gap_s, 0.1) << m;
  EXPECT_LT(t.max_gap_s, 0.8) << m;
  // the cut was seen (within the link timeout, generously) and the force faded at the bound
  ASSERT_GT(t.first_lost_s, 0.0) << "the master never saw the link lost\n" << m;
  EXPECT_LT(t.first_lost_s - cut_at_s, 0.5) << m;
  EXPECT_GE(json_value(m, "link_losses"), 1.0) << m;
  EXPECT_LE(t.max_step_n, 2.0 * rate_bound / rate_hz + 1e-9) << m;
  // with the link lost the force faded over the link fade (0.2 s), it did not jump to zero: a
  // tenth of a newton per cycle is generous (a fade of the session's force takes thousandths)
  EXPECT_LE(t.window_step_n, 0.1) << m;
}

TEST(Trust, TcpLinkCutKeepsTheHapticLoopsPeriod) {
  // not beside the multi-host sessions (six processes at 1 kHz each), which take the same lock
  const int lock_fd = open("/tmp/teleop_multi_host_test.lock", O_CREAT | O_RDWR, 0666);
  if (lock_fd >= 0) flock(lock_fd, LOCK_EX);
  struct Unlock {
    int fd;
    ~Unlock() {
      if (fd >= 0) close(fd);
    }
  } unlock{lock_fd};
  NetnsLab lab(2);
  if (!lab.create()) {
    std::printf("trust_test TcpLinkCut: SKIPPED: %s\n", lab.why().c_str());
    GTEST_SKIP() << "cannot build the test network: " << lab.why();
  }
  const std::string d = std::to_string(domains::kTcpLinkCut);
  const std::string mj = tmp("tcp_cut_master.json"), log = tmp("tcp_cut_master_log.csv");
  std::remove(mj.c_str());
  std::remove(log.c_str());
  const std::string h1 = NetnsLab::address(1);
  auto server = on_host(
      lab, 1, kServerBinary,
      {"--domain", d, "--profile", "wan_tcp_server", "--listen", "5100", "--public-address", h1,
       "--duration", "60", "--quiet", "--scene", scene_file("default.yaml"), "--insecure"},
      "tcp_server");
  auto master = on_host(lab, 2, kMasterBinary,
                        {"--domain", d, "--profile", "wan_tcp_client", "--peer", h1 + ":5100",
                         "--duration", "6", "--homing", "0.5", "--wait-server", "20", "--log", log,
                         "--summary-json", mj, "--quiet", "--insecure"},
                        "tcp_master");
  // the cut: 2 s into the session, for 1 s
  const double cut_at_s = two_seconds_into_the_session(log);
  ASSERT_GE(cut_at_s, 0.0) << "the session never started: " << master->err();
  ASSERT_NO_FATAL_FAILURE(cut_master_link_for_a_second(lab));
  const int rc = master->wait_for(60.0);
  server->signal(SIGTERM);
  server->wait_for(20.0);
  // a second of a 6 s session without a link loses a sixth of the commands: degraded (exit 5)
  const std::string m = Process::slurp(mj);
  ASSERT_EQ(rc, 5) << master->err() << m;
  EXPECT_EQ(json_text(m, "verdict"), "degraded") << m;
  expect_period_kept_through_the_cut(m, log, cut_at_s);
}

}  // namespace
}  // namespace teleop::test
