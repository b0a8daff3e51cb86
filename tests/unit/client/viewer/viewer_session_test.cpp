// The viewer's session state without a window: which server it watches, the receive rates and
// frame times the panel shows, the end-of-run summary, and how the robot is drawn.
#include "client/viewer/viewer_session.hpp"

#include <gtest/gtest.h>

#include <string>

namespace teleop::viewer {
namespace {

constexpr std::int64_t kT0 = 5'000'000'000;  // the run's start [ns]
constexpr std::int64_t kMs = 1'000'000;

ServerWatch::Prefix prefix(unsigned char last) {
  ServerWatch::Prefix p;
  p.value[0] = 0x0f;
  p.value[11] = last;
  return p;
}

TEST(ServerWatch, TheWriterOfTheNewestSlaveStateIsTheServerAndEveryWriterIsCounted) {
  ServerWatch w;
  EXPECT_EQ(w.server(), "");
  EXPECT_EQ(w.writers(), 0);
  w.note(prefix(1), false);  // statistics alone name no server
  EXPECT_EQ(w.server(), "");
  EXPECT_EQ(w.writers(), 1);
  w.note(prefix(1), true);
  EXPECT_EQ(w.server(), "0f000000.00000000.00000001");
  EXPECT_EQ(w.writers(), 1);
  // a second server on the domain: it is the one reported, and two writers are counted
  w.note(prefix(2), true);
  EXPECT_EQ(w.server(), "0f000000.00000000.00000002");
  EXPECT_EQ(w.writers(), 2);
  w.note(prefix(1), false);
  EXPECT_EQ(w.server(), "0f000000.00000000.00000002");
  EXPECT_EQ(w.writers(), 2);
}

TEST(ViewerSession, RatesAreCountedPerSecondFromWhatArrivedSinceTheLastRefresh) {
  ViewerSession session(10.0, kT0);
  EXPECT_FALSE(session.update_rates(kT0));  // the first call starts the count
  for (int i = 0; i < 100; ++i) {
    session.on_slave_state(SlaveState(), prefix(1), kT0 + i * 10 * kMs);
  }
  for (int i = 0; i < 60; ++i) session.data().on_master_state(MasterState(), kT0 + i * kMs);
  for (int i = 0; i < 4; ++i) {
    session.on_server_stats(ServerStats(), prefix(3), kT0 + i * kMs);
  }
  for (int i = 0; i < 30; ++i)
    session.record_frame(kT0 + i * 40 * kMs, kT0 + i * 40 * kMs + 2 * kMs);
  EXPECT_FALSE(session.update_rates(kT0 + 999 * kMs));  // less than a second: no refresh
  EXPECT_EQ(session.status().slave_hz, 0.0);
  ASSERT_TRUE(session.update_rates(kT0 + 2000 * kMs));
  const ReceiveStatus& s = session.status();
  EXPECT_DOUBLE_EQ(s.slave_hz, 50.0);
  EXPECT_DOUBLE_EQ(s.master_hz, 30.0);
  EXPECT_DOUBLE_EQ(s.stats_hz, 2.0);
  EXPECT_DOUBLE_EQ(s.mesh_hz, 0.0);
  EXPECT_DOUBLE_EQ(s.fps, 15.0);
  EXPECT_NEAR(s.frame_ms_p50, 2.0, 1e-9);
  EXPECT_NEAR(s.frame_ms_p99, 2.0, 1e-9);
  EXPECT_EQ(s.server, "0f000000.00000000.00000001");
  EXPECT_EQ(s.servers, 2);  // the slave states' writer and the statistics' writer
  // the next second counts only what came after the refresh
  for (int i = 0; i < 10; ++i) session.on_slave_state(SlaveState(), prefix(2), kT0);
  ASSERT_TRUE(session.update_rates(kT0 + 3000 * kMs));
  EXPECT_DOUBLE_EQ(session.status().slave_hz, 10.0);
  EXPECT_DOUBLE_EQ(session.status().fps, 0.0);
  EXPECT_EQ(session.status().server, "0f000000.00000000.00000002");
  EXPECT_EQ(session.status().servers, 3);
}

TEST(ViewerSession, TheSummaryCountsTheFramesOfThisRun) {
  ViewerSession session(10.0, kT0);
  RenderSetup setup;
  setup.width = 1280;
  setup.height = 720;
  setup.msaa = 4;
  setup.renderer = "llvmpipe (LLVM 15.0.6, 256 bits)";
  EXPECT_EQ(session.frame_summary(setup, kT0 + 1000 * kMs, 0.5), "");  // nothing drawn
  // 8 frames of 1 ms and 2 of 11 ms over 4 s, with 0.2 s of CPU
  for (int i = 0; i < 10; ++i) {
    const std::int64_t start = kT0 + i * 100 * kMs;
    session.record_frame(start, start + (i < 8 ? 1 : 11) * kMs);
  }
  EXPECT_EQ(session.frames(), 10u);
  const std::string text = session.frame_summary(setup, kT0 + 4000 * kMs, 0.2);
  EXPECT_EQ(text.rfind("teleop_viewer: 10 frames in 4.0 s (2.5 fps); ", 0), 0u) << text;
  EXPECT_NE(text.find("p50 1.00 ms"), std::string::npos) << text;
  EXPECT_NE(text.find("max 11.00 ms"), std::string::npos) << text;
  EXPECT_NE(text.find("CPU 20.0 ms per frame (all threads, 5% of a core)"), std::string::npos)
      << text;
  EXPECT_NE(text.find("1280x720, 4x MSAA, llvmpipe (LLVM 15.0.6, 256 bits)"), std::string::npos)
      << text;
  EXPECT_EQ(text.back(), ')') << "no line end: the caller prints it";
}

TEST(ViewerSession, ProcessCpuTimeIsCountedAndNeverGoesBack) {
  const double before = process_cpu_s();
  volatile double x = 0.0;
  for (int i = 0; i < 20'000'000; ++i) x = x + 1e-9 * i;
  EXPECT_GE(process_cpu_s(), before);
  EXPECT_GT(before, 0.0);
}

TEST(RobotStatus, SaysHowTheRobotIsDrawn) {
  ViewerView view;
  EXPECT_STREQ(robot_status(view, 0), "robot: -");
  view.scene_version = 1;
  view.scene.joint_count(0);
  EXPECT_STREQ(robot_status(view, 0), "no robot: a free tool (orange)");
  view.scene.joint_count(6);
  EXPECT_STREQ(robot_status(view, 6), "robot: skeleton from the scene's frames");
  EXPECT_STREQ(robot_status(view, 0), "robot: tip only (no link frames in the scene)");
}

}  // namespace
}  // namespace teleop::viewer
