#pragma once
// The viewer's Dear ImGui layer: the plot panel on the right (force, penetration and
// deformation, step time, loop rate, round trip, master energy, events) and a small overlay in
// the 3-D view. Plots are drawn with ImDrawList line strips over the time series.
#include <string>

#include "client/viewer/camera.hpp"
#include "client/viewer/viewer_data.hpp"

namespace teleop::viewer {

/// Everything the panel shows besides the data itself.
struct PanelInfo {
  int domain = 0;
  std::string profile;
  std::string server;  ///< GUID prefix of the server watched ("" none yet)
  int servers = 0;     ///< participants that wrote the server's topics (more than 1: a warning)
  double now_s = 0.0;  ///< plot clock [s since the viewer started]
  double history_s = 10.0;  ///< plot window [s]
  // receive rates of the last second [Hz]
  double slave_hz = 0.0, master_hz = 0.0, mesh_hz = 0.0, stats_hz = 0.0;
  // rendering
  double fps = 0.0;
  double frame_ms_p50 = 0.0, frame_ms_p99 = 0.0;
  bool headless = false;  ///< a snapshot: no frame rate to show
  int width = 0, height = 0, msaa = 0;
  bool paused = false;
  bool wireframe = false;
  bool displacement_colors = false;
  double max_displacement_m = 0.0;  ///< largest displacement from the first frame [m]
  std::string robot_status;         ///< how the robot is drawn
  std::string note;                 ///< one-line message (e.g. "saved snapshot.png")
};

/// Draws the panel into the column [layout.view_width, width) x [0, height).
void draw_panel(const ViewerView& view, const PanelInfo& info, const Layout& layout);

/// Draws the overlay text in the top-left corner of the 3-D view.
void draw_overlay(const ViewerView& view, const PanelInfo& info);

}  // namespace teleop::viewer
