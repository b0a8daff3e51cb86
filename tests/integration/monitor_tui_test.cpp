// teleop_monitor as people and scripts use it: the screen refreshed in place under tmux
// (send-keys, capture-pane), and the --json line mode.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <thread>

#include "server/deformable/deformable.hpp"
#include "tests/support/domains.hpp"
#include "tests/support/integration.hpp"
#include "tests/support/process.hpp"

namespace teleop::test {
namespace {

const std::string kMonitorBinary = std::string(TELEOP_BINARY_DIR) + "/client/teleop_monitor";

/// Output of a shell command (stdout), "" on failure.
std::string run(const std::string& cmd) {
  std::array<char, 4096> buf{};
  std::string out;
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(cmd.c_str(), "r"), pclose);
  if (!pipe) return out;
  while (fgets(buf.data(), buf.size(), pipe.get())) out += buf.data();
  return out;
}

/// A tmux server of this test only (own socket), killed at the end.
class Tmux {
 public:
  Tmux() : socket_("teleop_test_monitor_" + std::to_string(getpid())) {}
  ~Tmux() {
    // the monitor ends on SIGHUP and deletes its DDS entities; if it had to be killed harder,
    // its shared-memory segments would be left: clean them as the other tests do
    const bool was_alive = alive();
    std::system((base() + " kill-server >/dev/null 2>&1").c_str());
    if (was_alive) {
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
      std::system("fastdds shm clean >/dev/null 2>&1");
    }
  }
  std::string base() const { return "tmux -L " + socket_; }
  bool start(const std::string& command) {
    return std::system(
               (base() + " new-session -d -s mon -x 150 -y 45 '" + command + "'").c_str()) == 0;
  }
  std::string capture() const { return run(base() + " capture-pane -p -t mon"); }
  std::string capture_history() const { return run(base() + " capture-pane -p -S - -t mon"); }
  void keys(const std::string& k) { std::system((base() + " send-keys -t mon " + k).c_str()); }
  bool alive() const {
    return std::system((base() + " has-session -t mon 2>/dev/null").c_str()) == 0;
  }
  /// Polls the pane until `pred` holds (true) or timeout_s passes (false).
  template <class Pred>
  bool wait_screen(Pred pred, double timeout_s, std::string* last = nullptr) {
    std::string s;
    for (int i = 0; i < static_cast<int>(timeout_s * 10); ++i) {
      s = capture();
      if (pred(s)) {
        if (last) *last = s;
        return true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    if (last) *last = s;
    return false;
  }

 private:
  std::string socket_;
};

/// The line of the screen that starts with `prefix`.
std::string line_of(const std::string& screen, const std::string& prefix) {
  std::size_t p = 0;
  while (p < screen.size()) {
    const auto e = screen.find('\n', p);
    const std::string line = screen.substr(p, e == std::string::npos ? std::string::npos : e - p);
    if (line.rfind(prefix, 0) == 0) return line;
    if (e == std::string::npos) break;
    p = e + 1;
  }
  return "";
}

std::size_t occurrences(const std::string& text, const std::string& needle) {
  std::size_t n = 0;
  for (auto p = text.find(needle); p != std::string::npos; p = text.find(needle, p + 1)) ++n;
  return n;
}

TEST(MonitorTui, WaitsThenShowsLiveThenStaleAndQuitsOnQ) {
  if (std::system("command -v tmux >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "tmux is not installed (deploy/setup.sh installs it): the screen mode of "
                    "teleop_monitor is not tested here";
  }
  const std::string d = std::to_string(domains::kMonitorTui);
  Tmux tmux;
  ASSERT_TRUE(tmux.start(kMonitorBinary + " --domain " + d + " --stale 0.5"));
  std::string screen;
  // 1. nothing on the domain yet
  ASSERT_TRUE(tmux.wait_screen(
      [&](const std::string& s) {
        return s.find("waiting for a server on domain " + d + " (profile loopback)") !=
               std::string::npos;
      },
      30.0, &screen))
      << screen;
  // 2. a server and a short master session: live rates
  Process server(kServerBinary,
                 {"--domain", d, "--duration", "60", "--scene", scene_file("tool_only.yaml")},
                 "mon_server");
  Process master(kMasterBinary, {"--domain", d, "--duration", "1.5", "--homing", "0.3", "--quiet"},
                 "mon_master");
  ASSERT_TRUE(tmux.wait_screen(
      [](const std::string& s) {
        const std::string ms = line_of(s, "master_state");
        return s.find("status  LIVE") != std::string::npos && !ms.empty() &&
               ms.find("STALE") == std::string::npos && ms.find(" 0.0 ") == std::string::npos &&
               s.find("scene 'tool-only'") != std::string::npos &&
               s.find("master  rtt") != std::string::npos;
      },
      60.0, &screen))
      << screen;
  std::printf("[ live     ]\n%s\n", screen.c_str());
  EXPECT_NE(screen.find("server started"), std::string::npos) << screen;  // events as they come
  // 3. the master ends: its topics turn STALE and its values are no longer shown as live
  ASSERT_EQ(master.wait_for(60.0), 0) << master.err();
  ASSERT_TRUE(tmux.wait_screen(
      [](const std::string& s) {
        return line_of(s, "master_state").find("STALE") != std::string::npos &&
               s.find("master  STALE") != std::string::npos;
      },
      30.0, &screen))
      << screen;
  EXPECT_EQ(screen.find("master  rtt"), std::string::npos) << screen;
  EXPECT_EQ(line_of(screen, "slave_state").find("STALE"), std::string::npos) << screen;
  // 4. the screen was refreshed in place, not scrolled: one header in the whole pane history
  EXPECT_EQ(occurrences(tmux.capture_history(), "teleop_monitor  domain"), 1u)
      << tmux.capture_history();
  // 5. the server goes: the status says so
  server.signal(SIGTERM);
  ASSERT_EQ(server.wait_for(20.0), 0);
  ASSERT_TRUE(tmux.wait_screen(
      [](const std::string& s) { return s.find("STALE: no slave_state") != std::string::npos; },
      30.0, &screen))
      << screen;
  // 6. q quits
  tmux.keys("q");
  for (int i = 0; i < 100 && tmux.alive(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_FALSE(tmux.alive()) << tmux.capture();
}

TEST(MonitorTui, JsonLinesForScripts) {
  const std::string d = std::to_string(domains::kMonitorJson);
  Process mon(kMonitorBinary, {"--domain", d, "--json", "--period", "0.2", "--duration", "1"},
              "mon_json");
  ASSERT_EQ(mon.wait_for(30.0), 0) << mon.err();
  const std::string out = mon.out();
  std::size_t lines = 0;
  std::size_t p = 0;
  while (p < out.size()) {
    const auto e = out.find('\n', p);
    const std::string line = out.substr(p, e - p);
    ++lines;
    EXPECT_EQ(line.front(), '{') << line;
    EXPECT_EQ(line.back(), '}') << line;
    EXPECT_NE(line.find("\"waiting\": true"), std::string::npos) << line;
    EXPECT_NE(line.find("\"slave_state\": {\"count\": 0"), std::string::npos) << line;
    EXPECT_NE(line.find("\"slave\": null"), std::string::npos) << line;
    if (e == std::string::npos) break;
    p = e + 1;
  }
  EXPECT_GE(lines, 3u) << out;
  // bad flags exit 2 naming the flag, value and range
  Process bad(kMonitorBinary, {"--domain", d, "--stale", "0"}, "mon_bad");
  EXPECT_EQ(bad.wait_for(20.0), 2);
  EXPECT_NE(bad.err().find("--stale: '0' is out of the allowed range"), std::string::npos)
      << bad.err();
}

// The scene line says each deformable body's automatic step (docs/deformable.md): the default
// scene's FEM ball is stable at 1 ms, one sub-step.
TEST(MonitorTui, TheSceneLineSaysEachDeformablesStableStep) {
  const std::string d = std::to_string(domains::kMonitorScene);
  Process server(kServerBinary, {"--domain", d, "--quiet"}, "mon_scene_server");
  Process mon(kMonitorBinary, {"--domain", d, "--json", "--period", "0.5", "--duration", "4"},
              "mon_scene");
  ASSERT_EQ(mon.wait_for(60.0), 0) << mon.err();
  server.signal(SIGINT);
  server.wait_for(10.0);
  const std::string out = mon.out();
  const std::size_t at = out.find("{\"type\": \"scene\"");
  ASSERT_NE(at, std::string::npos) << out;
  const std::string line = out.substr(at, out.find('\n', at) - at);
  EXPECT_NE(line.find("\"deformables\": [{\"id\": 10, \"highest_frequency_radps\": "),
            std::string::npos)
      << line;
  EXPECT_NE(line.find("\"substeps\": 1}]"), std::string::npos) << line;
  EXPECT_GT(json_value(line, "stable_step_s"), 1e-3) << line;
  // and an info event says what runs the body: the FEM ball, mass-scaled to one step per 1 ms
  EXPECT_NE(out.find("\"message\": \"deformable 10: fem symplectic_euler, kernel scalar, 885 "
                     "nodes (477 on the surface), 3835 tetrahedra, 1 sub-step(s) per step\""),
            std::string::npos)
      << out;
}

}  // namespace
}  // namespace teleop::test
