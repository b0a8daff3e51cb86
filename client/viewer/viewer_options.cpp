#include "client/viewer/viewer_options.hpp"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "common/config/config.hpp"

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

}  // namespace

void validate_options(const ViewerOptions& o) {
  using config::check_flag;
  check_flag("--after", o.after_s, 0.0, 3600.0);
  check_flag("--timeout", o.timeout_s, 0.1, 3600.0);
  check_flag("--width", o.width, 320, 7680);
  check_flag("--height", o.height, 240, 4320);
  check_flag("--fps", o.fps, 0.0, 1000.0);
  check_flag("--history", o.history_s, 1.0, 600.0);
  check_flag("--duration", o.duration_s, 0.0, 1e7);
  if (o.msaa) check_flag("--msaa", *o.msaa, 0, 16);
  check_flag("--nice", o.nice, 0, 19);
  check_flag("--force-scale", o.force_scale_m_per_n, 1e-4, 10.0);
  check_flag("--displacement-scale", o.displacement_scale_m, 1e-5, 1.0);
  check_flag("--drive-scale", o.drive_scale, 1e-3, 1e3);
  check_flag("--drive-peak-force", o.drive_peak_force_n, 0.1, 1000.0);
  if (!o.drive && (!o.input_script.empty() || !o.drive_json.empty())) {
    throw config::ConfigError("command line: --input-script and --drive-json need --drive");
  }
  if (o.drive && !o.snapshot.empty()) {
    throw config::ConfigError("command line: --drive needs a window; it cannot go with --snapshot");
  }
  if (!o.snapshot.empty()) validate_snapshot_path(o.snapshot);
}

}  // namespace teleop::viewer
