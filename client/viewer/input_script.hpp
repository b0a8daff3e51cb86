#pragma once
// Scripted input for teleop_viewer --drive (--input-script FILE): what a person would do with
// the mouse, the keys and the tuning panel, at given times, so that a headless test (Xvfb) can
// drive a session through the viewer's own input handlers. One action per line:
//
//   # comment
//   <t_s> drag <dx_px> <dy_px> <seconds>   press on the master's hand, move the pointer by
//                                          (dx, dy) pixels over that time, release
//   <t_s> key <up|down|left|right|pageup|pagedown> <seconds>   hold a key (world +y, -y, -x,
//                                          +x, +z, -z)
//   <t_s> tune <field> <value> [<field> <value> ...]   fill the tuning panel and press Apply;
//                                          fields: master_stiffness_n_per_m,
//                                          master_damping_ns_per_m, force_gain,
//                                          slave_stiffness_n_per_m, forward_delay_ms,
//                                          backward_delay_ms, ramp_s
//   <t_s> snapshot <file.png>              save the window as it is drawn next
//   <t_s> quit                             close the viewer
//
// Times count from the first frame after the master's hand is known (MasterState received).
// Values are not range-checked here (the master checks requests: a script may send a bad one
// on purpose); syntax is, with file, line and what was expected.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

namespace teleop::viewer {

struct ScriptAction {
  enum class Kind { kDrag, kKey, kTune, kSnapshot, kQuit };
  double at_s = 0.0;
  Kind kind = Kind::kQuit;
  double dx_px = 0.0, dy_px = 0.0;  ///< drag
  double duration_s = 0.0;          ///< drag, key
  Eigen::Vector3d key_direction = Eigen::Vector3d::Zero();
  // tune: TUNE_* bits and values (delays in ms, as the panel shows them)
  std::uint32_t fields = 0;
  double master_stiffness_n_per_m = 0.0, master_damping_ns_per_m = 0.0, force_gain = 0.0,
         slave_stiffness_n_per_m = 0.0, forward_delay_ms = 0.0, backward_delay_ms = 0.0;
  double ramp_s = 0.5;
  std::string path;  ///< snapshot: the PNG to write
  std::string text;  ///< the line, for the log
};

/// Parses a script; actions sorted by time. @throws config::ConfigError naming file and line.
std::vector<ScriptAction> parse_input_script(const std::string& path);
/// Parses script text (`where` names it in errors). @throws config::ConfigError.
std::vector<ScriptAction> parse_input_script_text(const std::string& text,
                                                  const std::string& where);

}  // namespace teleop::viewer
