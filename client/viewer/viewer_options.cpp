#include "client/viewer/viewer_options.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "common/config/config.hpp"
#include "common/config/flags.hpp"
#include "common/dds/network_flags.hpp"

namespace teleop::viewer {

namespace {

/// --snapshot: a .png name (any case) in a directory that exists.
void validate_snapshot_path(const std::string& snapshot) {
  const std::filesystem::path p(snapshot);
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext != ".png") {
    throw config::ConfigError("command line: --snapshot " + snapshot +
                              ": the file name must end in .png");
  }
  const std::filesystem::path dir = p.has_parent_path() ? p.parent_path() : ".";
  if (!std::filesystem::is_directory(dir)) {
    throw config::ConfigError("command line: --snapshot " + snapshot + ": the directory " +
                              dir.string() + " does not exist");
  }
}

/// The session's flags: DDS, the snapshot, the window and the plots.
void add_view_flags(CLI::App& app, ViewerOptions& o, dds::NetworkFlags& net) {
  using config::add_integer;
  using config::add_number;
  add_integer(app, "--domain", o.domain, 0.0, 232.0,
              "DDS domain id (default: $TELEOP_DOMAIN or 0)");
  app.add_option("--profile", o.profile, "Fast DDS profile (default: loopback)");
  dds::add_network_flags(app, net);
  app.add_option("--snapshot", o.snapshot,
                 "headless: render offscreen, write this PNG and exit (needs an X display, e.g. "
                 "xvfb-run)");
  add_number(app, "--after", o.after_s, 0.0, 3600.0,
             "snapshot after this many seconds of complete data", "s")
      ->capture_default_str();
  add_number(app, "--timeout", o.timeout_s, 0.1, 3600.0,
             "snapshot: give up (exit 3) when the data is not complete by then", "s")
      ->capture_default_str();
  add_integer(app, "--width", o.width, 320.0, 7680.0, "window or snapshot width", "px")
      ->capture_default_str();
  add_integer(app, "--height", o.height, 240.0, 4320.0, "window or snapshot height", "px")
      ->capture_default_str();
  add_number(app, "--fps", o.fps, 0.0, 1000.0,
             "frame rate cap (0 = the display rate (vsync), or 15 on a software renderer "
             "(llvmpipe))",
             "Hz")
      ->capture_default_str();
  add_number(app, "--history", o.history_s, 1.0, 600.0, "plot window", "s")->capture_default_str();
  add_number(app, "--duration", o.duration_s, 0.0, 1e7, "close after this long (0 = until closed)",
             "s");
  add_integer(app, "--msaa", o.msaa, 0.0, 16.0,
              "samples per pixel for anti-aliasing (default: 4; 0 in a window drawn by a "
              "software renderer such as llvmpipe)");
  add_number(app, "--force-scale", o.force_scale_m_per_n, 1e-4, 10.0,
             "contact force arrow length per newton", "m/N")
      ->capture_default_str();
  add_number(app, "--displacement-scale", o.displacement_scale_m, 1e-5, 1.0,
             "deformation drawn fully red", "m")
      ->capture_default_str();
  add_integer(app, "--nice", o.nice, 0.0, 19.0,
              "scheduling niceness of the viewer (it yields the CPU to the server and master on "
              "the same machine)")
      ->capture_default_str();
}

/// The display switches and the drive's flags.
void add_drive_flags(CLI::App& app, ViewerOptions& o) {
  app.add_flag("--full-rate", o.full_rate,
               "read the 1 kHz state topics instead of the 60 Hz *_view copies; loads the loops");
  app.add_flag("--hide-panel", o.hide_panel, "start without the plot panel (key H)");
  app.add_flag("--wireframe", o.wireframe, "start with wireframe meshes (key W)");
  app.add_flag("--drive", o.drive,
               "drive the session by hand: be the master's device (teleop_master --device "
               "external) and its tuning tool (teleop_master --accept-tuning)");
  app.add_option("--input-script", o.input_script,
                 "with --drive: play mouse, key and tuning input from this file (docs/tools.md)");
  app.add_option("--drive-json", o.drive_json, "with --drive: write the drive summary here");
  config::add_number(app, "--drive-scale", o.drive_scale, 1e-3, 1e3,
                     "slave metres per device metre (the master's position scale)")
      ->capture_default_str();
  config::add_number(app, "--drive-peak-force", o.drive_peak_force_n, 0.1, 1000.0,
                     "the device's declared peak force (the force bar's full scale)", "N")
      ->capture_default_str();
  app.add_flag("--plain", o.plain_colours,
               "start with meshes in their plain colour instead of coloured by deformation "
               "(key C)");
}

}  // namespace

void add_viewer_flags(CLI::App& app, ViewerOptions& o, dds::NetworkFlags& net) {
  add_view_flags(app, o, net);
  add_drive_flags(app, o);
}

void validate_options(const ViewerOptions& o) {
  if (!o.drive && (!o.input_script.empty() || !o.drive_json.empty())) {
    throw config::ConfigError("command line: --input-script and --drive-json need --drive");
  }
  if (o.drive && !o.snapshot.empty()) {
    throw config::ConfigError("command line: --drive needs a window; it cannot go with --snapshot");
  }
  if (!o.snapshot.empty()) validate_snapshot_path(o.snapshot);
}

}  // namespace teleop::viewer
