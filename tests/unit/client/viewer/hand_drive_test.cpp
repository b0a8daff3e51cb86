// Driving by hand (teleop_viewer --drive): the pointer's ray back through the camera, a drag in
// the plane facing the camera, the workspace box, the speed and acceleration limits, and the
// scripted input's syntax errors.
#include "client/viewer/hand_drive.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "client/viewer/camera.hpp"
#include "client/viewer/input_script.hpp"
#include "common/config/config.hpp"

namespace teleop::viewer {
namespace {

TEST(OrbitCamera, ARayThroughAPixelProjectsBackOntoIt) {
  const OrbitCamera c;
  for (const Eigen::Vector2f& px : {Eigen::Vector2f(450.0f, 360.0f), Eigen::Vector2f(10.0f, 700.0f),
                                    Eigen::Vector2f(880.0f, 20.0f)}) {
    Eigen::Vector3f o, d;
    c.ray(px, 900.0f, 720.0f, o, d);
    EXPECT_NEAR(d.norm(), 1.0f, 1e-5f);
    Eigen::Vector2f back;
    ASSERT_TRUE(c.project(o + 1.7f * d, 900.0f, 720.0f, back));
    EXPECT_NEAR(back.x(), px.x(), 0.05f);
    EXPECT_NEAR(back.y(), px.y(), 0.05f);
  }
}

TEST(HandDrive, ADragMovesTheTargetByWhatThePointerMovedInThePlaneFacingTheCamera) {
  const OrbitCamera c;
  HandDriveParams p;
  p.position_scale = 2.0;  // slave metres per device metre
  HandDrive drive(p);
  const Eigen::Vector3d hand = c.target.cast<double>();
  Eigen::Vector2f at;
  ASSERT_TRUE(c.project(c.target, 900.0f, 720.0f, at));
  Eigen::Vector3f o, d;
  c.ray(at, 900.0f, 720.0f, o, d);
  drive.grab(hand, c.forward().cast<double>(), o.cast<double>(), d.cast<double>());
  ASSERT_TRUE(drive.dragging());
  // 20 px up on screen: the screen's up in the plane facing the camera (its world z is the cosine
  // of the camera's elevation), 20 px worth of metres
  c.ray(at - Eigen::Vector2f(0.0f, 20.0f), 900.0f, 720.0f, o, d);
  drive.drag(o.cast<double>(), d.cast<double>());
  const double metres = 20.0 / static_cast<double>(c.pixels_per_metre(c.target, 720.0f));
  EXPECT_NEAR(drive.target_m().norm(), metres / 2.0, 1e-3 * metres);
  EXPECT_NEAR(drive.target_m().z(), std::cos(c.elevation_rad) * drive.target_m().norm(),
              1e-3 * drive.target_m().norm());
  EXPECT_NEAR(drive.target_m().dot(c.forward().cast<double>()), 0.0, 1e-6);  // in the plane
  drive.release();
  c.ray(at, 900.0f, 720.0f, o, d);
  const Eigen::Vector3d kept = drive.target_m();
  drive.drag(o.cast<double>(), d.cast<double>());  // not dragging: nothing moves
  EXPECT_EQ(drive.target_m(), kept);
}

TEST(HandDrive, TheTargetStaysInTheWorkspaceAndTheHandleIsSpeedAndAccelerationLimited) {
  HandDriveParams p;
  p.workspace_half_m = 0.1;
  p.max_speed_mps = 0.2;
  p.max_accel_mps2 = 5.0;
  HandDrive drive(p);
  drive.set_target(Eigen::Vector3d(1.0, 0.0, -0.05));  // a pointer jump far out
  EXPECT_EQ(drive.target_m(), Eigen::Vector3d(0.1, 0.0, -0.05));
  double max_speed = 0.0, max_accel = 0.0;
  Eigen::Vector3d v_prev = Eigen::Vector3d::Zero();
  for (int i = 0; i < 3000; ++i) {
    drive.advance(1e-3);
    max_speed = std::max(max_speed, drive.velocity_mps().norm());
    max_accel = std::max(max_accel, (drive.velocity_mps() - v_prev).norm() / 1e-3);
    v_prev = drive.velocity_mps();
  }
  EXPECT_LE(max_speed, 0.2 + 1e-9);
  EXPECT_LE(max_accel, 5.0 * 1.05 + 1e-6);  // the last step onto the target may round
  EXPECT_LT((drive.position_m() - drive.target_m()).norm(), 1e-9);
  EXPECT_EQ(drive.velocity_mps(), Eigen::Vector3d::Zero());
  // keys: 0.05 m/s for 0.4 s
  drive.nudge(-Eigen::Vector3d::UnitZ(), 0.4);
  EXPECT_NEAR(drive.target_m().z(), -0.07, 1e-12);
  drive.set_target(Eigen::Vector3d(std::nan(""), 0.0, 0.0));  // ignored
  EXPECT_NEAR(drive.target_m().z(), -0.07, 1e-12);
}

TEST(InputScript, ParsesActionsInTimeOrderAndNamesTheLineOfAMistake) {
  const auto a = parse_input_script_text(
      "# a comment\n2 tune force_gain 1.5 ramp_s 0.2\n0.5 key pagedown 0.4\n"
      "1 drag 10 -5 0.5  # trailing comment\n3 quit\n2.5 snapshot /tmp/x.png\n",
      "s.txt");
  ASSERT_EQ(a.size(), 5u);
  EXPECT_EQ(a[0].kind, ScriptAction::Kind::kKey);
  EXPECT_EQ(a[0].key_direction, -Eigen::Vector3d::UnitZ());
  EXPECT_EQ(a[1].kind, ScriptAction::Kind::kDrag);
  EXPECT_DOUBLE_EQ(a[1].dy_px, -5.0);
  EXPECT_EQ(a[2].kind, ScriptAction::Kind::kTune);
  EXPECT_EQ(a[2].fields, 4u);
  EXPECT_DOUBLE_EQ(a[2].force_gain, 1.5);
  EXPECT_DOUBLE_EQ(a[2].ramp_s, 0.2);
  EXPECT_EQ(a[3].kind, ScriptAction::Kind::kSnapshot);
  EXPECT_EQ(a[3].path, "/tmp/x.png");
  EXPECT_EQ(a[4].kind, ScriptAction::Kind::kQuit);
  const auto error = [](const std::string& text) {
    try {
      parse_input_script_text(text, "s.txt");
    } catch (const config::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error("\n1 jump\n")
                .find("s.txt:2: action 'jump' is not one of drag, key, tune, snapshot, quit"),
            std::string::npos);
  EXPECT_NE(error("1 key space 1\n").find("s.txt:1: key 'space' is not one of"), std::string::npos);
  EXPECT_NE(error("1 tune force_gain fast\n").find("s.txt:1: force_gain 'fast' is not a number"),
            std::string::npos);
  EXPECT_NE(error("1 tune gain 2\n").find("tuning field 'gain' is not one of"), std::string::npos);
  EXPECT_NE(error("1 drag 1 2 0\n").find("is out of the allowed range (0, 600]"),
            std::string::npos);
  EXPECT_NE(error("-1 quit\n").find("time -1 is negative"), std::string::npos);
  EXPECT_NE(error("x quit\n").find("time 'x' is not a number"), std::string::npos);
}

}  // namespace
}  // namespace teleop::viewer
