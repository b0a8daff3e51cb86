// teleop_viewer against real servers: a headless snapshot under Xvfb of the tool-only scene and
// of the default scene, checked pixel by pixel where the viewer's default camera must have put
// the tip sphere, the elastic sphere and the robot's base. The test learns the positions from
// the same DDS topics the viewer reads (it joins the domain as one more observer).
//
// Skipped (not failed) when the viewer was not built or xvfb-run is missing.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <sstream>
#include <thread>

#include "common/dds/endpoint.hpp"
#include "common/dds/scene_objects.hpp"
#include "common/util/clock.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"
#include "tests/support/domains.hpp"
#include "tests/support/integration.hpp"
#include "tests/support/process.hpp"
#ifdef TELEOP_HAVE_VIEWER
#include "client/viewer/camera.hpp"
#include "client/viewer/png.hpp"
#endif

namespace teleop::test {
namespace {

std::string tmp(const std::string& name) { return temp_path("viewer_it", name); }

#ifdef TELEOP_HAVE_VIEWER
#define SKIP_UNLESS_VIEWER_BUILT() (void)0
#else
#define SKIP_UNLESS_VIEWER_BUILT() \
  GTEST_SKIP() << "teleop_viewer not built (TELEOP_BUILD_VIEWER=OFF or its packages are missing)"
#endif

TEST(Viewer, CommandLineMistakesExit2NamingFlagValueAndRange) {
  SKIP_UNLESS_VIEWER_BUILT();
  // checked before any window opens: no display needed
  Process w(kViewerBinary, {"--width", "100000"}, "viewer_flag_w");
  EXPECT_EQ(w.wait_for(10.0), 2);
  EXPECT_NE(w.err().find("--width: '100000' is out of the allowed range [320, 7680]"),
            std::string::npos)
      << w.err();
  Process a(kViewerBinary, {"--after", "-1"}, "viewer_flag_a");
  EXPECT_EQ(a.wait_for(10.0), 2);
  EXPECT_NE(a.err().find("--after: '-1' is out of the allowed range [0, 3600]"), std::string::npos)
      << a.err();
  Process s(kViewerBinary, {"--snapshot", "/no/such/dir/x.png"}, "viewer_flag_s");
  EXPECT_EQ(s.wait_for(10.0), 2);
  EXPECT_NE(s.err().find("/no/such/dir"), std::string::npos) << s.err();
  Process j(kViewerBinary, {"--snapshot", tmp("x.jpg")}, "viewer_flag_j");
  EXPECT_EQ(j.wait_for(10.0), 2);
  EXPECT_NE(j.err().find(".png"), std::string::npos) << j.err();
  Process f(kViewerBinary, {"--fps", "fast"}, "viewer_flag_f");
  EXPECT_EQ(f.wait_for(10.0), 2);
  EXPECT_NE(f.err().find("--fps"), std::string::npos) << f.err();
}

#ifdef TELEOP_HAVE_VIEWER

/// Absolute path of an executable found on PATH, or "" when there is none.
std::string find_on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    const std::filesystem::path p = std::filesystem::path(dir.empty() ? "." : dir) / name;
    if (access(p.c_str(), X_OK) == 0) return p.string();
  }
  return "";
}

/// xvfb-run's path; the calling test skips when it is missing.
// NOLINTBEGIN(bugprone-macro-parentheses): var is the name the macro declares
#define REQUIRE_XVFB_RUN(var)                                                \
  const std::string var = find_on_path("xvfb-run");                          \
  if (var.empty())                                                           \
  GTEST_SKIP() << "xvfb-run not found (apt-get install xvfb xauth): cannot " \
                  "run the viewer without a display"
// NOLINTEND(bugprone-macro-parentheses)

/// The viewer under its own Xvfb. -n gives each test its own first display number to try, so
/// parallel tests do not race for the same one.
std::vector<std::string> xvfb_args(int domain, const std::vector<std::string>& viewer_args) {
  std::vector<std::string> a = {
      "-a", "-n", std::to_string(100 + domain), "-s", "-screen 0 1280x720x24", kViewerBinary};
  a.insert(a.end(), viewer_args.begin(), viewer_args.end());
  return a;
}

/// What the viewer will draw, read from the same topics by the test.
class SceneObserver {
 public:
  explicit SceneObserver(int domain)
      : participant_(dds::ParticipantOptions{"loopback", domain, "viewer-test"}),
        scene_reader_(participant_, dds::topics::kScene,
                      [this](const SceneDescription& s, const eprosima::fastdds::dds::SampleInfo&) {
                        std::lock_guard<std::mutex> l(m_);
                        scene_ = s;
                        have_scene_ = true;
                      }),
        slave_reader_(participant_, dds::topics::kSlaveState,
                      [this](const SlaveState& s, const eprosima::fastdds::dds::SampleInfo&) {
                        std::lock_guard<std::mutex> l(m_);
                        const auto& p = s.tip_position_m();
                        tip_ = Eigen::Vector3f(static_cast<float>(p[0]), static_cast<float>(p[1]),
                                               static_cast<float>(p[2]));
                        ++states_;
                      }) {}

  bool wait(double timeout_s) {
    const auto t0 = now_ns();
    while (seconds_between(t0, now_ns()) < timeout_s) {
      {
        std::lock_guard<std::mutex> l(m_);
        if (have_scene_ && states_ > 100) return true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
  }
  Eigen::Vector3f tip() {
    std::lock_guard<std::mutex> l(m_);
    return tip_;
  }
  SceneDescription scene() {
    std::lock_guard<std::mutex> l(m_);
    return scene_;
  }

 private:
  std::mutex m_;
  SceneDescription scene_;
  bool have_scene_ = false;
  Eigen::Vector3f tip_ = Eigen::Vector3f::Zero();
  int states_ = 0;
  dds::Participant participant_;
  dds::Reader<SceneDescriptionPubSubType> scene_reader_;
  dds::Reader<SlaveStatePubSubType> slave_reader_;
};

Eigen::Vector3f vec3(const std::array<double, 3>& a) {
  return Eigen::Vector3f(static_cast<float>(a[0]), static_cast<float>(a[1]),
                         static_cast<float>(a[2]));
}

// Colour classes of the renderer's palette under its lighting (client/viewer/gl/renderer.hpp):
// ratios, not values, since shading scales a colour.
bool is_tip(const std::uint8_t* p) {  // orange (0.98, 0.42, 0.08)
  return p[0] >= 90 && p[0] >= 1.5 * p[1] && p[0] >= 2.5 * p[2];
}
bool is_elastic_sphere(const std::uint8_t* p) {  // blue (0.30, 0.58, 0.92)
  return p[2] >= 90 && p[2] >= p[0] + 50 && p[2] >= p[1] + 15;
}
bool is_robot(const std::uint8_t* p) {  // steel grey-blue (0.55, 0.60, 0.68) / (0.36, 0.39, 0.45)
  const int r = p[0], g = p[1], b = p[2];
  return r + g + b >= 180 && b >= r + 6 && b <= 1.6 * r && g >= r - 4 && g <= b + 4;
}

/// Fraction of pixels within `radius` of `centre` for which `pred` holds.
template <class Pred>
double fraction_in_disc(const viewer::Image& img, const Eigen::Vector2f& centre, float radius,
                        Pred pred, int* count = nullptr) {
  int n = 0, hit = 0;
  for (int y = static_cast<int>(centre.y() - radius); y <= static_cast<int>(centre.y() + radius);
       ++y) {
    for (int x = static_cast<int>(centre.x() - radius); x <= static_cast<int>(centre.x() + radius);
         ++x) {
      if (x < 0 || y < 0 || x >= img.width || y >= img.height) continue;
      if ((Eigen::Vector2f(static_cast<float>(x), static_cast<float>(y)) - centre).norm() > radius)
        continue;
      ++n;
      if (pred(img.at(x, y))) ++hit;
    }
  }
  if (count) *count = hit;
  return n > 0 ? static_cast<double>(hit) / n : 0.0;
}

/// Pixels with x < width_limit for which `pred` holds.
template <class Pred>
int count_pixels(const viewer::Image& img, int width_limit, Pred pred) {
  int n = 0;
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < std::min(width_limit, img.width); ++x) n += pred(img.at(x, y)) ? 1 : 0;
  }
  return n;
}

constexpr int kWidth = 960, kHeight = 540;

/// Runs a server on `scene_file`, the viewer in snapshot mode, and returns the decoded PNG;
/// `observer` holds what the viewer was shown.
void snapshot_of(const std::string& scene_file, int domain, const std::string& tag,
                 std::unique_ptr<SceneObserver>& observer, viewer::Image& image,
                 const std::string& xvfb, std::string& path) {
  const std::string d = std::to_string(domain);
  Process server(kServerBinary, {"--domain", d, "--duration", "90", "--scene", scene_file},
                 tag + "_server");
  observer = std::make_unique<SceneObserver>(domain);
  ASSERT_TRUE(observer->wait(30.0)) << "no scene or slave state from the server\n" << server.err();
  // the viewer joins late: the scene and topology must reach it anyway (transient local)
  const std::string png = tmp(tag + ".png");
  std::filesystem::remove(png);
  Process viewer(xvfb,
                 xvfb_args(domain, {"--domain", d, "--snapshot", png, "--after", "1.0", "--width",
                                    std::to_string(kWidth), "--height", std::to_string(kHeight),
                                    "--timeout", "60"}),
                 tag + "_viewer");
  ASSERT_EQ(viewer.wait_for(150.0), 0) << viewer.out() << viewer.err();
  EXPECT_NE(viewer.err().find("wrote " + png), std::string::npos) << viewer.err();
  server.signal(SIGTERM);
  EXPECT_EQ(server.wait_for(20.0), 0) << server.err();
  std::string error;
  ASSERT_TRUE(viewer::read_png_file(png, image, error)) << error;
  path = png;
}

/// Removes the snapshot when the test passed; keeps it for a look when it failed.
void keep_on_failure(const std::string& png) {
  if (::testing::Test::HasFailure()) {
    std::cerr << "snapshot kept: " << png << "\n";
  } else {
    std::filesystem::remove(png);
  }
}

/// Checks common to every scene: size, not blank, the panel drawn, the tip where the camera
/// puts it and nowhere else.
void check_frame_and_tip(const viewer::Image& img, const Eigen::Vector3f& tip, float tip_radius_m) {
  ASSERT_EQ(img.width, kWidth);
  ASSERT_EQ(img.height, kHeight);
  ASSERT_EQ(img.channels, 3);
  // not blank: many distinct colours, and no single colour covers most of the picture
  std::vector<int> histogram(1 << 15, 0);
  for (int y = 0; y < img.height; ++y) {
    for (int x = 0; x < img.width; ++x) {
      const std::uint8_t* p = img.at(x, y);
      ++histogram[static_cast<std::size_t>(((p[0] >> 3) << 10) | ((p[1] >> 3) << 5) | (p[2] >> 3))];
    }
  }
  const int distinct = static_cast<int>(
      std::count_if(histogram.begin(), histogram.end(), [](int n) { return n > 0; }));
  const int most = *std::max_element(histogram.begin(), histogram.end());
  EXPECT_GT(distinct, 100);
  EXPECT_LT(most, 0.7 * kWidth * kHeight);

  const viewer::Layout layout = viewer::layout_for(kWidth, kHeight, true);
  // the panel (right column) has text and plots: bright pixels
  int bright = 0;
  for (int y = 0; y < img.height; ++y) {
    for (int x = layout.view_width; x < img.width; ++x) {
      const std::uint8_t* p = img.at(x, y);
      bright += (p[0] + p[1] + p[2] > 450) ? 1 : 0;
    }
  }
  EXPECT_GT(bright, 300) << "the plot panel looks empty";

  // the tip: the default camera projects it here, this big
  const viewer::OrbitCamera camera;
  Eigen::Vector2f px;
  ASSERT_TRUE(camera.project(tip, static_cast<float>(layout.view_width),
                             static_cast<float>(layout.view_height), px));
  ASSERT_GT(px.x(), 0.0f);
  ASSERT_LT(px.x(), static_cast<float>(layout.view_width));
  ASSERT_GT(px.y(), 0.0f);
  ASSERT_LT(px.y(), static_cast<float>(kHeight));
  const float r_px = tip_radius_m * camera.pixels_per_metre(tip, static_cast<float>(kHeight));
  ASSERT_GT(r_px, 5.0f);
  int near_tip = 0;
  const double core = fraction_in_disc(img, px, 0.6f * r_px, is_tip);
  fraction_in_disc(img, px, 1.3f * r_px, is_tip, &near_tip);
  const int all_tip = count_pixels(img, layout.view_width, is_tip);  // the 3-D view only
  EXPECT_GT(core, 0.6) << "tip colour at (" << px.x() << ", " << px.y() << "), r " << r_px
                       << " px: " << core;
  EXPECT_GT(near_tip, 0.35 * M_PI * static_cast<double>(r_px * r_px))
      << "the tip is hidden or too small";
  EXPECT_GT(near_tip, 0.9 * all_tip)
      << "tip-coloured pixels far from where the tip is: " << all_tip - near_tip;
}

TEST(Viewer, SnapshotOfTheToolOnlySceneShowsTheToolWhereTheCameraPutsIt) {
  SKIP_UNLESS_VIEWER_BUILT();
  REQUIRE_XVFB_RUN(xvfb);
  std::unique_ptr<SceneObserver> observer;
  viewer::Image img;
  std::string png;
  snapshot_of(scene_file("tool_only.yaml"), domains::kViewerToolScene, "tool", observer, img, xvfb,
              png);
  if (HasFatalFailure()) return;
  const SceneDescription scene = observer->scene();
  EXPECT_EQ(scene.joint_count(), 0u);
  check_frame_and_tip(img, observer->tip(), static_cast<float>(scene.tip_radius_m()));
  keep_on_failure(png);
}

TEST(Viewer, SnapshotOfTheDefaultSceneShowsTipElasticSphereAndRobot) {
  SKIP_UNLESS_VIEWER_BUILT();
  REQUIRE_XVFB_RUN(xvfb);
  std::unique_ptr<SceneObserver> observer;
  viewer::Image img;
  std::string png;
  snapshot_of(scene_file("default.yaml"), domains::kViewerDefaultScene, "default", observer, img,
              xvfb, png);
  if (HasFatalFailure()) return;
  const SceneDescription scene = observer->scene();
  ASSERT_EQ(scene.joint_count(), 6u);
  check_frame_and_tip(img, observer->tip(), static_cast<float>(scene.tip_radius_m()));

  const viewer::Layout layout = viewer::layout_for(kWidth, kHeight, true);
  const viewer::OrbitCamera camera;
  const auto vw = static_cast<float>(layout.view_width), vh = static_cast<float>(kHeight);
  bool saw_sphere = false, saw_base = false;
  for (const auto& o : scene.objects()) {
    Eigen::Vector2f px;
    if (o.kind() == OBJECT_DEFORMABLE_MESH) {
      // the elastic sphere: its centre region (the tip hovers above it, out of the way)
      saw_sphere = true;
      const Eigen::Vector3f c = vec3(o.position_m());
      ASSERT_TRUE(camera.project(c, vw, vh, px));
      const float r_px = static_cast<float>(o.size_m()[0]) * camera.pixels_per_metre(c, vh);
      const double f = fraction_in_disc(img, px, 0.4f * r_px, is_elastic_sphere);
      EXPECT_GT(f, 0.7) << "elastic sphere at (" << px.x() << ", " << px.y() << "): " << f;
    } else if (o.kind() == OBJECT_ROBOT_LINK && o.id() == scene_objects::kRobotFrameIdBase) {
      // the robot's base joint (a sphere of 0.045 m on the skeleton)
      saw_base = true;
      const Eigen::Vector3f b = vec3(o.position_m());
      ASSERT_TRUE(camera.project(b, vw, vh, px));
      const float r_px = 0.045f * camera.pixels_per_metre(b, vh);
      const double f = fraction_in_disc(img, px, 0.6f * r_px, is_robot);
      EXPECT_GT(f, 0.5) << "robot base at (" << px.x() << ", " << px.y() << "): " << f;
    }
  }
  EXPECT_TRUE(saw_sphere) << "the default scene has an elastic sphere";
  EXPECT_TRUE(saw_base) << "the scene description carries the robot's frames";
  keep_on_failure(png);
}

TEST(Viewer, SnapshotWithoutAServerGivesUpWithExit3) {
  SKIP_UNLESS_VIEWER_BUILT();
  REQUIRE_XVFB_RUN(xvfb);
  const std::string png = tmp("nodata.png");
  Process viewer(
      xvfb,
      xvfb_args(domains::kViewerNoData, {"--domain", std::to_string(domains::kViewerNoData),
                                         "--snapshot", png, "--timeout", "1.5"}),
      "viewer_nodata");
  EXPECT_EQ(viewer.wait_for(60.0), 3) << viewer.err();
  EXPECT_NE(viewer.err().find("missing: teleop/scene, teleop/slave_state"), std::string::npos)
      << viewer.err();
  EXPECT_FALSE(std::filesystem::exists(png));
}

#endif  // TELEOP_HAVE_VIEWER

}  // namespace
}  // namespace teleop::test
