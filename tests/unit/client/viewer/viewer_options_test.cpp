// teleop_viewer's command-line checks without a process: each refusal names the flag, the value
// and the allowed range (exit 2 in the app), and the drive and snapshot flags go together only
// where they can.
#include "client/viewer/viewer_options.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <string>

#include "common/config/config.hpp"

namespace teleop::viewer {
namespace {

/// The message validate_options() refuses `o` with ("" when it accepts them).
std::string refusal(const ViewerOptions& o) {
  try {
    validate_options(o);
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(ViewerOptions, TheDefaultsAreAccepted) {
  EXPECT_EQ(refusal(ViewerOptions{}), "");
  ViewerOptions drive;
  drive.drive = true;
  drive.input_script = "script.txt";
  drive.drive_json = "drive.json";
  EXPECT_EQ(refusal(drive), "");
}

TEST(ViewerOptions, ANumberOutOfRangeIsRefusedNamingFlagValueAndRange) {
  struct Case {
    std::function<void(ViewerOptions&)> set;
    std::string message;
  };
  const Case cases[] = {
      {[](ViewerOptions& o) { o.width = 100000; },
       "--width 100000 is out of the allowed range [320, 7680]"},
      {[](ViewerOptions& o) { o.height = 100; }, "--height 100 is out of the allowed range"},
      {[](ViewerOptions& o) { o.after_s = -1.0; },
       "--after -1 is out of the allowed range [0, 3600]"},
      {[](ViewerOptions& o) { o.timeout_s = 0.0; }, "--timeout 0 is out of the allowed range"},
      {[](ViewerOptions& o) { o.fps = 2000.0; }, "--fps 2000 is out of the allowed range"},
      {[](ViewerOptions& o) { o.history_s = 0.5; }, "--history 0.5 is out of the allowed range"},
      {[](ViewerOptions& o) { o.duration_s = -3.0; }, "--duration -3 is out of the allowed range"},
      {[](ViewerOptions& o) { o.msaa = 32; }, "--msaa 32 is out of the allowed range [0, 16]"},
      {[](ViewerOptions& o) { o.nice = 20; }, "--nice 20 is out of the allowed range [0, 19]"},
      {[](ViewerOptions& o) { o.force_scale_m_per_n = 0.0; }, "--force-scale 0 is out of"},
      {[](ViewerOptions& o) { o.displacement_scale_m = 2.0; }, "--displacement-scale 2 is out of"},
      {[](ViewerOptions& o) { o.drive_scale = 1e4; }, "--drive-scale 10000 is out of"},
      {[](ViewerOptions& o) { o.drive_peak_force_n = 0.0; }, "--drive-peak-force 0 is out of"},
  };
  for (const Case& c : cases) {
    ViewerOptions o;
    c.set(o);
    const std::string m = refusal(o);
    EXPECT_NE(m.find(c.message), std::string::npos)
        << "expected '" << c.message << "', got '" << m << "'";
  }
}

TEST(ViewerOptions, TheDriveFlagsNeedDriveAndAWindow) {
  ViewerOptions script;
  script.input_script = "script.txt";
  EXPECT_NE(refusal(script).find("--input-script and --drive-json need --drive"),
            std::string::npos);
  ViewerOptions json;
  json.drive_json = "drive.json";
  EXPECT_NE(refusal(json).find("need --drive"), std::string::npos);
  ViewerOptions headless;
  headless.drive = true;
  headless.snapshot = "x.png";
  EXPECT_NE(refusal(headless).find("--drive needs a window"), std::string::npos);
}

TEST(ViewerOptions, TheSnapshotIsAPngInADirectoryThatExists) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path();
  ViewerOptions o;
  o.snapshot = (dir / "view.PNG").string();  // any case
  EXPECT_EQ(refusal(o), "");
  o.snapshot = "view.png";  // the working directory
  EXPECT_EQ(refusal(o), "");
  o.snapshot = (dir / "view.jpg").string();
  EXPECT_NE(refusal(o).find("the file name must end in .png"), std::string::npos);
  o.snapshot = "/no/such/dir/x.png";
  EXPECT_NE(refusal(o).find("the directory /no/such/dir does not exist"), std::string::npos);
}

}  // namespace
}  // namespace teleop::viewer
