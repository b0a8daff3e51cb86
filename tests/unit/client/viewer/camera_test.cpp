#include "client/viewer/camera.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace teleop::viewer {
namespace {

TEST(OrbitCamera, TheTargetProjectsToTheViewportCentre) {
  const OrbitCamera c;
  Eigen::Vector2f px;
  ASSERT_TRUE(c.project(c.target, 900.0f, 720.0f, px));
  EXPECT_NEAR(px.x(), 450.0f, 1e-2f);
  EXPECT_NEAR(px.y(), 360.0f, 1e-2f);
}

TEST(OrbitCamera, UpIsUpAndScaleMatchesTheFieldOfView) {
  const OrbitCamera c;
  Eigen::Vector2f centre, above;
  ASSERT_TRUE(c.project(c.target, 900.0f, 720.0f, centre));
  // 0.1 m straight up: higher on screen (smaller y), same column
  ASSERT_TRUE(c.project(c.target + Eigen::Vector3f(0, 0, 0.1f), 900.0f, 720.0f, above));
  EXPECT_LT(above.y(), centre.y());
  EXPECT_NEAR(above.x(), centre.x(), 1e-2f);
  // a length across the view at the target spans pixels_per_metre pixels per metre
  const Eigen::Vector3f right = (c.target - c.eye()).cross(Eigen::Vector3f::UnitZ()).normalized();
  Eigen::Vector2f side;
  ASSERT_TRUE(c.project(c.target + 0.1f * right, 900.0f, 720.0f, side));
  EXPECT_NEAR((side - centre).norm(), 0.1f * c.pixels_per_metre(c.target, 720.0f), 0.5f);
  EXPECT_GT(side.x(), centre.x());  // camera right is screen right
  // by hand: half the height (360 px) spans tan(fov / 2) * distance
  EXPECT_NEAR(c.pixels_per_metre(c.target, 720.0f),
              360.0f / (std::tan(0.5f * c.fov_y_rad) * c.distance_m), 0.01f);
}

TEST(OrbitCamera, PointsBehindTheCameraDoNotProject) {
  const OrbitCamera c;
  Eigen::Vector2f px;
  const Eigen::Vector3f behind = c.eye() + (c.eye() - c.target);
  EXPECT_FALSE(c.project(behind, 900.0f, 720.0f, px));
}

TEST(OrbitCamera, OrbitPanAndZoomMoveTheView) {
  OrbitCamera c;
  const OrbitCamera home;
  c.zoom(2.0f);
  EXPECT_NEAR(c.distance_m, home.distance_m * 0.81f, 1e-4f);
  c.orbit(100.0f, 1e6f);
  EXPECT_LE(c.elevation_rad, 1.5f);  // never over the pole
  c.pan(10.0f, 0.0f, 720.0f);
  EXPECT_GT((c.target - home.target).norm(), 0.0f);
  EXPECT_NEAR(c.target.z(), home.target.z(), 1e-5f);  // a horizontal drag pans sideways
}

TEST(Layout, PanelOnTheRightAndTheViewFillsTheRest) {
  const Layout l = layout_for(1280, 720, true);
  EXPECT_EQ(l.panel_width, 384);
  EXPECT_EQ(l.view_width + l.panel_width, 1280);
  EXPECT_EQ(l.view_height, 720);
  EXPECT_EQ(layout_for(1280, 720, false).view_width, 1280);
  EXPECT_GE(layout_for(320, 240, true).view_width, 160);
}

}  // namespace
}  // namespace teleop::viewer
