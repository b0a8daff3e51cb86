// teleop_viewer's command-line checks without a process: each number flag's refusal names the
// flag, the value and the allowed range (exit 2 in the app), and the drive and snapshot flags go
// together only where they can.
#include "client/viewer/viewer_options.hpp"

#include <gtest/gtest.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "common/config/config.hpp"
#include "common/config/flags.hpp"
#include "common/dds/participant.hpp"

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

/// The message the viewer's flags refuse `args` with ("" when they accept them); `o` gets the
/// values.
std::string flag_refusal(std::vector<std::string> args, ViewerOptions& o) {
  CLI::App app;
  dds::NetworkFlags net;
  add_viewer_flags(app, o, net);
  config::harden_flags(app);
  std::reverse(args.begin(), args.end());  // CLI11 takes the arguments last first
  try {
    app.parse(args);
  } catch (const CLI::ParseError& e) {
    return e.what();
  }
  return "";
}

TEST(ViewerOptions, ANumberOutOfRangeIsRefusedNamingFlagValueAndRange) {
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  const Case cases[] = {
      {{"--width", "100000"}, "--width: '100000' is out of the allowed range [320, 7680]"},
      {{"--height", "100"}, "--height: '100' is out of the allowed range"},
      {{"--after", "-1"}, "--after: '-1' is out of the allowed range [0, 3600]"},
      {{"--timeout", "0"}, "--timeout: '0' is out of the allowed range"},
      {{"--fps", "2000"}, "--fps: '2000' is out of the allowed range"},
      {{"--history", "0.5"}, "--history: '0.5' is out of the allowed range"},
      {{"--duration", "-3"}, "--duration: '-3' is out of the allowed range"},
      {{"--msaa", "32"}, "--msaa: '32' is out of the allowed range [0, 16]"},
      {{"--nice", "20"}, "--nice: '20' is out of the allowed range [0, 19]"},
      {{"--force-scale", "0"}, "--force-scale: '0' is out of"},
      {{"--displacement-scale", "2"}, "--displacement-scale: '2' is out of"},
      {{"--drive-scale", "1e4"}, "--drive-scale: '1e4' is out of"},
      {{"--drive-peak-force", "0"}, "--drive-peak-force: '0' is out of"},
      {{"--width", ""}, "--width: '' is empty"},
      {{"--duration", "-0"}, "--duration: '-0' is negative"},
      {{"--width", "1280.5"}, "--width: '1280.5' is not a whole number"},
  };
  for (const Case& c : cases) {
    ViewerOptions o;
    const std::string m = flag_refusal(c.args, o);
    EXPECT_NE(m.find(c.message), std::string::npos)
        << "expected '" << c.message << "', got '" << m << "'";
  }
}

TEST(ViewerOptions, TheFlagsSetTheOptionsAndTheHelpGivesEachRange) {
  ViewerOptions o;
  EXPECT_EQ(
      flag_refusal({"--width", "320", "--msaa", "0", "--drive-scale", "0.5", "--domain", "7"}, o),
      "");
  EXPECT_EQ(o.width, 320);
  EXPECT_EQ(o.msaa, std::optional<int>(0));
  EXPECT_DOUBLE_EQ(o.drive_scale, 0.5);
  EXPECT_EQ(o.domain, std::optional<int>(7));
  EXPECT_EQ(refusal(o), "");
  CLI::App app;
  dds::NetworkFlags net;
  ViewerOptions defaults;
  add_viewer_flags(app, defaults, net);
  const std::string help = app.help();
  EXPECT_NE(help.find("window or snapshot width [px], [320, 7680]"), std::string::npos) << help;
  EXPECT_NE(help.find("deformation drawn fully red [m], [1e-5, 1]"), std::string::npos) << help;
  EXPECT_NE(help.find("=1280"), std::string::npos) << help;  // the default
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
