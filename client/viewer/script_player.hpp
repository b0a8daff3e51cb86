#pragma once
// Plays an input script (teleop_viewer --drive --input-script, client/viewer/input_script.hpp)
// through the same DriveInput calls the mouse and keys use: a drag presses on the master's hand
// where the camera shows it and moves the pointer linearly, a key is held for its duration, a
// tune fills the form and presses Apply. Times count from the first step at which the master's
// hand is known. Each action is logged as it starts.
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "client/viewer/camera.hpp"
#include "client/viewer/drive_input.hpp"
#include "client/viewer/input_script.hpp"
#include "client/viewer/viewer_data.hpp"

namespace teleop::viewer {

/// What a step asks of the app.
struct ScriptStep {
  bool quit = false;      ///< a quit action: close the viewer
  bool save = false;      ///< a snapshot action: save the window as it is drawn next
  std::string save_path;  ///< where the save goes
};

class ScriptPlayer {
 public:
  /// `actions` sorted by time (parse_input_script gives them so); `log` takes one line per
  /// action and the start.
  ScriptPlayer(std::vector<ScriptAction> actions, std::ostream& log);

  /// Render thread, once per frame at `now_ns` (steady clock): moves the drag and the held key
  /// under way, then starts every action due. `layout` is the 3-D view the pointer moves in.
  ScriptStep step(std::int64_t now_ns, const ViewerView& view, const OrbitCamera& camera,
                  const Layout& layout, DriveInput& input);

  /// A scripted drag is under way (the mouse cannot grab the hand meanwhile).
  bool dragging() const { return dragging_; }
  /// Every action started and nothing is under way.
  bool done() const { return next_ >= actions_.size() && !dragging_ && key_until_s_ < 0.0; }

 private:
  void continue_drag(double t_s, const OrbitCamera& camera, const Layout& layout,
                     DriveInput& input);
  void continue_key(double t_s, DriveInput& input);
  /// Starts `a`; returns false for quit.
  bool start(const ScriptAction& a, const ViewerView& view, const OrbitCamera& camera,
             const Layout& layout, DriveInput& input, ScriptStep& out);

  std::vector<ScriptAction> actions_;
  std::size_t next_ = 0;  ///< the first action not started
  std::ostream& log_;
  std::int64_t t0_ns_ = 0;  ///< 0 until the master's hand is known
  ScriptAction drag_;       ///< the drag under way (when dragging_)
  bool dragging_ = false;
  Eigen::Vector2f press_px_ = Eigen::Vector2f::Zero();
  Eigen::Vector3d key_dir_ = Eigen::Vector3d::Zero();
  double key_last_s_ = 0.0;    ///< script time the held key has moved the target up to [s]
  double key_until_s_ = -1.0;  ///< the held key's release [s]; negative: none held
};

/// A tune action typed into the form: the fields it names, and its ramp.
void fill_tuning_form(const ScriptAction& tune, TuningForm& form);

}  // namespace teleop::viewer
