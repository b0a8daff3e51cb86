// When the viewer draws: the frame period it chooses, the switch to the display's rate when
// vsync does not throttle, no catching up after a late frame, and when a headless snapshot is
// taken or given up.
#include "client/viewer/frame_timing.hpp"

#include <gtest/gtest.h>

namespace teleop::viewer {
namespace {

constexpr std::int64_t kMs = 1'000'000;

TEST(FramePacer, ThePeriodIsFpsElseThirtyHeadlessElseFifteenInSoftwareElseVsync) {
  EXPECT_DOUBLE_EQ(FramePacer(50.0, true, true, 0).period_s(), 0.02);
  EXPECT_DOUBLE_EQ(FramePacer(0.0, true, true, 0).period_s(), 1.0 / 30.0);
  EXPECT_DOUBLE_EQ(FramePacer(0.0, false, true, 0).period_s(), 1.0 / 15.0);
  EXPECT_DOUBLE_EQ(FramePacer(0.0, false, false, 0).period_s(), 0.0);
}

TEST(FramePacer, AVsyncThatDoesNotThrottleIsPacedAtTheDisplayRate) {
  FramePacer vsync(0.0, false, false, 0);
  EXPECT_FALSE(vsync.vsync_check_due(119));
  EXPECT_TRUE(vsync.vsync_check_due(FramePacer::kVsyncCheckFrames));
  EXPECT_FALSE(vsync.pace_if_unthrottled(70.0, 60.0)) << "within 25%: the display throttles";
  EXPECT_DOUBLE_EQ(vsync.period_s(), 0.0);
  EXPECT_EQ(vsync.sleep_ns(10 * kMs, 10 * kMs), 0);
  EXPECT_TRUE(vsync.pace_if_unthrottled(900.0, 60.0));
  EXPECT_DOUBLE_EQ(vsync.period_s(), 1.0 / 60.0);
  EXPECT_FALSE(vsync.vsync_check_due(FramePacer::kVsyncCheckFrames)) << "checked once";
  FramePacer fixed(20.0, false, false, 0);
  EXPECT_FALSE(fixed.vsync_check_due(FramePacer::kVsyncCheckFrames));
  EXPECT_FALSE(fixed.pace_if_unthrottled(900.0, 60.0)) << "--fps chose the rate";
  EXPECT_DOUBLE_EQ(fixed.period_s(), 0.05);
}

TEST(FramePacer, FramesAreDueEveryPeriodAndALateOneDoesNotCatchUp) {
  FramePacer p(100.0, false, false, 1000 * kMs);  // 10 ms
  // a 3 ms frame: sleep to the next 10 ms mark
  EXPECT_EQ(p.sleep_ns(1003 * kMs, 1003 * kMs), 7 * kMs);
  // a 25 ms frame: late; the next frame starts now, not at the marks it missed
  EXPECT_EQ(p.sleep_ns(1035 * kMs, 1035 * kMs), 0);
  EXPECT_EQ(p.sleep_ns(1037 * kMs, 1038 * kMs), 7 * kMs);  // due at 1045 ms
}

TEST(SnapshotGate, ShootsAfterTheWaitOnceTheDataIsCompleteAndThreeFramesWereLaidOut) {
  SnapshotGate gate(2.0, 30.0);
  EXPECT_FALSE(gate.frame(false, 100 * kMs, 0.1).shoot);
  const SnapshotFrame ready = gate.frame(true, 1000 * kMs, 1.0);
  EXPECT_TRUE(ready.became_complete);
  EXPECT_FALSE(ready.shoot);
  const SnapshotFrame next = gate.frame(true, 1500 * kMs, 1.5);
  EXPECT_FALSE(next.became_complete);
  EXPECT_FALSE(next.shoot) << "0.5 s of the 2 s wait";
  // complete once is enough: a frame that misses a mesh does not reset the wait
  EXPECT_FALSE(gate.frame(false, 2000 * kMs, 2.0).shoot);
  const SnapshotFrame shot = gate.frame(true, 3000 * kMs, 3.0);
  EXPECT_TRUE(shot.shoot);
  EXPECT_FALSE(shot.give_up);
}

TEST(SnapshotGate, WithNoWaitItStillLaysTheUiOutOverThreeFrames) {
  SnapshotGate gate(0.0, 30.0);
  EXPECT_FALSE(gate.frame(true, 1 * kMs, 0.001).shoot);
  EXPECT_FALSE(gate.frame(true, 2 * kMs, 0.002).shoot);
  EXPECT_TRUE(gate.frame(true, 3 * kMs, 0.003).shoot);
}

TEST(SnapshotGate, GivesUpWhenTheDataIsNotCompleteWithinTheTimeout) {
  SnapshotGate gate(2.0, 5.0);
  EXPECT_FALSE(gate.frame(false, 5000 * kMs, 5.0).give_up);
  EXPECT_TRUE(gate.frame(false, 5100 * kMs, 5.1).give_up);
  SnapshotGate late(2.0, 5.0);
  late.frame(true, 4000 * kMs, 4.0);
  EXPECT_FALSE(late.frame(true, 5100 * kMs, 5.1).give_up) << "complete in time: no timeout";
}

}  // namespace
}  // namespace teleop::viewer
