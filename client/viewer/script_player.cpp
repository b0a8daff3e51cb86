#include "client/viewer/script_player.hpp"

#include <algorithm>
#include <utility>

#include "common/util/clock.hpp"

namespace teleop::viewer {

ScriptPlayer::ScriptPlayer(std::vector<ScriptAction> actions, std::ostream& log)
    : actions_(std::move(actions)), log_(log) {}

ScriptStep ScriptPlayer::step(std::int64_t now_ns, const ViewerView& view,
                              const OrbitCamera& camera, const Layout& layout, DriveInput& input) {
  ScriptStep out;
  if (done()) return out;
  if (t0_ns_ == 0) {
    Eigen::Vector3d hand;
    if (!hand_world(view, hand)) return out;  // times count from when the hand is known
    t0_ns_ = now_ns;
    log_ << "teleop_viewer: input script starts (the master's hand is known)\n";
  }
  const double t = seconds_between(t0_ns_, now_ns);
  if (dragging_) continue_drag(t, camera, layout, input);
  if (key_until_s_ >= 0.0) continue_key(t, input);
  while (next_ < actions_.size() && actions_[next_].at_s <= t) {
    const ScriptAction& a = actions_[next_++];
    log_ << "teleop_viewer: script t=" << t << " s:" << a.text << "\n";
    if (!start(a, view, camera, layout, input, out)) {
      out.quit = true;
      break;
    }
  }
  return out;
}

void ScriptPlayer::continue_drag(double t_s, const OrbitCamera& camera, const Layout& layout,
                                 DriveInput& input) {
  // the pointer moves linearly from its press point
  const double s = std::clamp((t_s - drag_.at_s) / drag_.duration_s, 0.0, 1.0);
  const Eigen::Vector2f by(static_cast<float>(drag_.dx_px), static_cast<float>(drag_.dy_px));
  input.move(press_px_ + static_cast<float>(s) * by, camera, layout);
  if (s >= 1.0) {
    input.release();
    dragging_ = false;
  }
}

void ScriptPlayer::continue_key(double t_s, DriveInput& input) {
  const double until = std::min(t_s, key_until_s_);
  input.keys(key_dir_, until - key_last_s_);
  key_last_s_ = until;
  if (t_s >= key_until_s_) key_until_s_ = -1.0;
}

bool ScriptPlayer::start(const ScriptAction& a, const ViewerView& view, const OrbitCamera& camera,
                         const Layout& layout, DriveInput& input, ScriptStep& out) {
  switch (a.kind) {
    case ScriptAction::Kind::kDrag: {
      Eigen::Vector3d hand;
      Eigen::Vector2f at;
      if (hand_world(view, hand) &&
          camera.project(hand.cast<float>(), static_cast<float>(layout.view_width),
                         static_cast<float>(layout.view_height), at) &&
          input.press(at, view, camera, layout)) {
        press_px_ = at;
        drag_ = a;
        dragging_ = true;
      } else {
        log_ << "teleop_viewer: script: the master's hand is not on screen; drag skipped\n";
      }
      return true;
    }
    case ScriptAction::Kind::kKey:
      key_dir_ = a.key_direction;
      key_last_s_ = a.at_s;
      key_until_s_ = a.at_s + a.duration_s;
      return true;
    case ScriptAction::Kind::kTune:
      // type the script's fields into the form, then press Apply with those fields
      fill_tuning_form(a, input.form());
      input.send_tuning(a.fields);
      return true;
    case ScriptAction::Kind::kSnapshot:
      out.save = true;  // written after the next frame is drawn
      out.save_path = a.path;
      return true;
    case ScriptAction::Kind::kQuit:
      return false;
  }
  return true;
}

void fill_tuning_form(const ScriptAction& a, TuningForm& form) {
  if (a.fields & TUNE_MASTER_STIFFNESS) form.master_stiffness_n_per_m = a.master_stiffness_n_per_m;
  if (a.fields & TUNE_MASTER_DAMPING) form.master_damping_ns_per_m = a.master_damping_ns_per_m;
  if (a.fields & TUNE_FORCE_GAIN) form.force_gain = a.force_gain;
  if (a.fields & TUNE_SLAVE_STIFFNESS) form.slave_stiffness_n_per_m = a.slave_stiffness_n_per_m;
  if (a.fields & TUNE_FORWARD_DELAY) form.forward_delay_ms = a.forward_delay_ms;
  if (a.fields & TUNE_BACKWARD_DELAY) form.backward_delay_ms = a.backward_delay_ms;
  form.ramp_s = a.ramp_s;
}

}  // namespace teleop::viewer
