// Driving by hand without a window: a press grabs the master's hand only near its ring, a mouse
// drag follows the pointer until the button is let go, held keys move along the world axes, and
// an input script plays its drags, keys, tunings, snapshots and quit at their times through the
// same calls. The drive is a HandDrive behind a recording DriveTarget (no DDS).
#include "client/viewer/script_player.hpp"

#include <gtest/gtest.h>

#include <sstream>
#include <vector>

#include "client/viewer/drive_input.hpp"
#include "client/viewer/hand_drive.hpp"
#include "client/viewer/input_script.hpp"

namespace teleop::viewer {
namespace {

constexpr std::int64_t kT0 = 7'000'000'000;  // steady clock [ns]
constexpr std::int64_t kMs = 1'000'000;

/// A HandDrive that keeps the tuning requests it was sent.
class RecordingTarget : public DriveTarget {
 public:
  void grab(const Eigen::Vector3d& anchor, const Eigen::Vector3d& view_dir,
            const Eigen::Vector3d& o, const Eigen::Vector3d& d) override {
    drive.grab(anchor, view_dir, o, d);
  }
  void drag(const Eigen::Vector3d& o, const Eigen::Vector3d& d) override { drive.drag(o, d); }
  void release() override { drive.release(); }
  bool dragging() const override { return drive.dragging(); }
  void nudge(const Eigen::Vector3d& direction, double dt_s) override {
    drive.nudge(direction, dt_s);
  }
  void send_tuning(const TuningRequest& r) override { tunings.push_back(r); }

  HandDrive drive;
  std::vector<TuningRequest> tunings;
};

/// A view in which the master's hand is at `hand_m`.
ViewerView view_with_hand(const Eigen::Vector3d& hand_m) {
  ViewerView v;
  v.have_master = true;
  v.master.command_position_m({hand_m.x(), hand_m.y(), hand_m.z()});
  return v;
}

/// Where `camera` shows `p` in `layout`'s 3-D view.
Eigen::Vector2f on_screen(const OrbitCamera& camera, const Layout& layout,
                          const Eigen::Vector3d& p) {
  Eigen::Vector2f px;
  EXPECT_TRUE(camera.project(p.cast<float>(), static_cast<float>(layout.view_width),
                             static_cast<float>(layout.view_height), px));
  return px;
}

/// Metres in the plane of the hand per pixel on screen.
double metres_per_px(const OrbitCamera& camera, const Layout& layout) {
  return 1.0 / static_cast<double>(
                   camera.pixels_per_metre(camera.target, static_cast<float>(layout.view_height)));
}

class DriveTest : public ::testing::Test {
 protected:
  OrbitCamera camera;
  Layout layout = layout_for(1280, 720, true);
  Eigen::Vector3d hand = camera.target.cast<double>();
  ViewerView view = view_with_hand(hand);
  RecordingTarget target;
  DriveInput input{target};
};

TEST_F(DriveTest, APressGrabsTheHandOnlyNearItsRingAndOnlyOnceItIsKnown) {
  const Eigen::Vector2f at = on_screen(camera, layout, hand);
  EXPECT_FALSE(input.press(at + Eigen::Vector2f(40.0f, 0.0f), view, camera, layout));
  EXPECT_FALSE(target.dragging());
  EXPECT_FALSE(input.press(at, ViewerView(), camera, layout)) << "no master state yet";
  EXPECT_FALSE(input.press(at, view_with_hand(Eigen::Vector3d::Zero()), camera, layout))
      << "a zero hand is not known yet";
  EXPECT_TRUE(input.press(at + Eigen::Vector2f(20.0f, 0.0f), view, camera, layout));
  EXPECT_TRUE(target.dragging());
}

TEST_F(DriveTest, AMouseDragFollowsThePointerUntilTheButtonIsLetGo) {
  const Eigen::Vector2f at = on_screen(camera, layout, hand);
  PointerInput p;
  p.position_px = at;
  p.left_clicked = true;
  p.left_down = true;
  // a shift-click pans the camera, a click over the UI or during the script's drag is theirs
  p.shift = true;
  EXPECT_FALSE(input.pointer(p, false, view, camera, layout));
  p.shift = false;
  p.ui_wants_mouse = true;
  EXPECT_FALSE(input.pointer(p, false, view, camera, layout));
  p.ui_wants_mouse = false;
  EXPECT_FALSE(input.pointer(p, true, view, camera, layout));
  EXPECT_FALSE(target.dragging());

  ASSERT_TRUE(input.pointer(p, false, view, camera, layout));
  ASSERT_TRUE(target.dragging());
  p.left_clicked = false;
  p.position_px = at - Eigen::Vector2f(0.0f, 20.0f);  // 20 px up
  EXPECT_TRUE(input.pointer(p, false, view, camera, layout));
  EXPECT_NEAR(target.drive.target_m().norm(), 20.0 * metres_per_px(camera, layout), 1e-4);
  EXPECT_GT(target.drive.target_m().z(), 0.0);
  p.left_down = false;  // let go: released, and the pointer is the drive's this frame still
  EXPECT_TRUE(input.pointer(p, false, view, camera, layout));
  EXPECT_FALSE(target.dragging());
  EXPECT_FALSE(input.pointer(p, false, view, camera, layout));
}

TEST(DriveKeys, HeldKeysGiveTheWorldAxes) {
  DriveKeys k;
  EXPECT_EQ(key_direction(k), Eigen::Vector3d::Zero());
  k.right = true;
  k.up = true;
  k.page_down = true;
  EXPECT_EQ(key_direction(k), Eigen::Vector3d(1.0, 1.0, -1.0));
  k.left = true;  // both ways at once: no motion on that axis
  k.down = true;
  k.page_up = true;
  EXPECT_EQ(key_direction(k), Eigen::Vector3d::Zero());
  DriveKeys back;
  back.left = true;
  back.down = true;
  back.page_up = true;
  EXPECT_EQ(key_direction(back), Eigen::Vector3d(-1.0, -1.0, 1.0));
}

TEST_F(DriveTest, AScriptWaitsForTheHandThenPlaysKeysTuningSnapshotAndQuitAtTheirTimes) {
  std::ostringstream log;
  ScriptPlayer script(parse_input_script_text("0.5 key right 1.0\n"
                                              "1.0 tune force_gain 0.5 ramp_s 0.2\n"
                                              "2.0 snapshot shot.png\n"
                                              "3.0 quit\n",
                                              "test"),
                      log);
  // no master state: the script's clock has not started, however late it is
  EXPECT_FALSE(script.step(kT0 + 9000 * kMs, ViewerView(), camera, layout, input).quit);
  EXPECT_EQ(log.str(), "");
  const std::int64_t start = kT0 + 10'000 * kMs;
  script.step(start, view, camera, layout, input);
  EXPECT_NE(log.str().find("input script starts"), std::string::npos) << log.str();
  script.step(start + 600 * kMs, view, camera, layout, input);  // the key goes down at 0.5 s
  EXPECT_EQ(target.drive.target_m(), Eigen::Vector3d::Zero());
  script.step(start + 1000 * kMs, view, camera, layout, input);  // held 0.5 s; the tuning
  const double speed = target.drive.params().key_speed_mps;
  EXPECT_NEAR(target.drive.target_m().x(), 0.5 * speed, 1e-12);
  ASSERT_EQ(target.tunings.size(), 1u);
  EXPECT_EQ(target.tunings[0].fields(), TUNE_FORCE_GAIN);
  EXPECT_DOUBLE_EQ(target.tunings[0].force_gain(), 0.5);
  EXPECT_DOUBLE_EQ(target.tunings[0].ramp_s(), 0.2);
  EXPECT_EQ(target.tunings[0].source(), "viewer");
  EXPECT_DOUBLE_EQ(input.form().force_gain, 0.5);  // typed into the form

  const ScriptStep snap = script.step(start + 2100 * kMs, view, camera, layout, input);
  EXPECT_NEAR(target.drive.target_m().x(), 1.0 * speed, 1e-12) << "released at 1.5 s";
  EXPECT_TRUE(snap.save);
  EXPECT_EQ(snap.save_path, "shot.png");
  EXPECT_FALSE(snap.quit);
  EXPECT_FALSE(script.done());
  EXPECT_TRUE(script.step(start + 3000 * kMs, view, camera, layout, input).quit);
  EXPECT_TRUE(script.done());
  EXPECT_NE(log.str().find("s:3.0 quit"), std::string::npos) << log.str();
}

TEST_F(DriveTest, AScriptedDragPressesOnTheHandAndMovesThePointerLinearly) {
  std::ostringstream log;
  ScriptPlayer script(parse_input_script_text("0 drag 0 -20 1.0\n", "test"), log);
  script.step(kT0, view, camera, layout, input);
  ASSERT_TRUE(script.dragging()) << log.str();
  ASSERT_TRUE(target.dragging());
  const double m_per_px = metres_per_px(camera, layout);
  script.step(kT0 + 500 * kMs, view, camera, layout, input);
  EXPECT_NEAR(target.drive.target_m().norm(), 10.0 * m_per_px, 1e-4);
  EXPECT_TRUE(script.dragging());
  script.step(kT0 + 1200 * kMs, view, camera, layout, input);  // past its end: the full 20 px
  EXPECT_NEAR(target.drive.target_m().norm(), 20.0 * m_per_px, 1e-4);
  EXPECT_FALSE(script.dragging());
  EXPECT_FALSE(target.dragging());
  EXPECT_TRUE(script.done());
}

TEST_F(DriveTest, AScriptedDragIsSkippedWhenTheHandIsNotOnScreen) {
  std::ostringstream log;
  ScriptPlayer script(parse_input_script_text("0 drag 0 -20 1.0\n", "test"), log);
  // behind the camera
  const Eigen::Vector3d behind = 2.0 * camera.eye().cast<double>() - hand;
  script.step(kT0, view_with_hand(behind), camera, layout, input);
  EXPECT_FALSE(script.dragging());
  EXPECT_FALSE(target.dragging());
  EXPECT_NE(log.str().find("the master's hand is not on screen; drag skipped"), std::string::npos)
      << log.str();
}

}  // namespace
}  // namespace teleop::viewer
