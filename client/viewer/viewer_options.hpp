#pragma once
// teleop_viewer's settings as the command line gives them: add_viewer_flags() declares the flags
// (each number with its range, checked on its text); validate_options() refuses what a range
// cannot say, a bad combination or snapshot name, before any window, file or participant is
// opened (exit 2).
#include <optional>
#include <string>

namespace CLI {
class App;
}  // namespace CLI

namespace teleop::dds {
struct NetworkFlags;
}  // namespace teleop::dds

namespace teleop::viewer {

struct ViewerOptions {
  std::optional<int> domain;
  std::optional<std::string> profile;
  std::string snapshot;     ///< headless: write this PNG and exit
  double after_s = 2.0;     ///< snapshot this long after the data is complete [s]
  double timeout_s = 30.0;  ///< snapshot: give up when the data is not complete by then [s]
  int width = 1280;         ///< window or snapshot width [px]
  int height = 720;         ///< window or snapshot height [px]
  double fps = 0.0;         ///< frame rate cap [Hz]; 0: the display rate (vsync)
  double history_s = 10.0;  ///< plot window [s]
  double duration_s = 0.0;  ///< close after this long [s]; 0: until closed
  std::optional<int> msaa;  ///< default: 4, or 0 in a window on a software renderer
  double force_scale_m_per_n = 0.25;    ///< contact force arrow length per newton [m/N]
  double displacement_scale_m = 0.003;  ///< deformation drawn fully red [m]
  int nice = 19;  ///< scheduling priority of every viewer thread (0 normal, 19 lowest)
  bool hide_panel = false;
  bool wireframe = false;
  bool plain_colours = false;  ///< start without the displacement colours (key C)
  bool full_rate = false;      ///< read the 1 kHz topics instead of the 60 Hz *_view copies
  // drive
  bool drive = false;                ///< be the master's device and tuning tool
  std::string input_script;          ///< scripted input (needs --drive)
  std::string drive_json;            ///< write the drive summary here at exit
  double drive_scale = 1.0;          ///< slave metres per device metre (the master's alpha)
  double drive_peak_force_n = 10.0;  ///< declared peak force of the device [N]
};

/// Declares every flag of teleop_viewer on `app`, bound to `o` and (the network flags) `net`.
void add_viewer_flags(CLI::App& app, ViewerOptions& o, dds::NetworkFlags& net);

/// Checks what the flags' ranges cannot: the drive flags against --drive and --snapshot, and the
/// snapshot's name (.png) and directory (exists).
/// @throws config::ConfigError naming the flag and the value.
void validate_options(const ViewerOptions& options);

}  // namespace teleop::viewer
