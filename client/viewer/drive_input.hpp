#pragma once
// Driving by hand (teleop_viewer --drive) without a window: where the master's hand is on
// screen, a press that grabs it, the drag, held keys and the tuning form, sent to a DriveTarget
// (the DriveSession, or a test's). The app reads the pointer and the keys from its window and
// hands them over; the input script (ScriptPlayer) goes through the same calls.
#include <Eigen/Core>
#include <cstdint>

#include "client/viewer/camera.hpp"
#include "client/viewer/viewer_data.hpp"
#include "teleop/idl/Teleop.h"

namespace teleop::viewer {

/// What the drive moves: the device handle that follows the pointer and keys, and the writer of
/// tuning requests. The DriveSession publishes them; a test records them.
class DriveTarget {
 public:
  virtual ~DriveTarget() = default;
  /// Starts a drag of `anchor_world_m` (the master's hand) in the plane facing `view_dir`.
  virtual void grab(const Eigen::Vector3d& anchor_world_m, const Eigen::Vector3d& view_dir,
                    const Eigen::Vector3d& ray_origin, const Eigen::Vector3d& ray_dir) = 0;
  /// Moves the drag with the pointer's ray.
  virtual void drag(const Eigen::Vector3d& ray_origin, const Eigen::Vector3d& ray_dir) = 0;
  virtual void release() = 0;
  virtual bool dragging() const = 0;
  /// Moves the target along the world axes `direction` for `dt_s` at the key speed.
  virtual void nudge(const Eigen::Vector3d& direction, double dt_s) = 0;
  /// Writes a tuning request (fields: TUNE_* bits; values in the request's units).
  virtual void send_tuning(const TuningRequest& request) = 0;
};

/// The tuning form's values (delays in ms, as shown).
struct TuningForm {
  bool loaded = false;         ///< filled from a status
  std::uint64_t answered = 0;  ///< request_seq of the status it was last filled from
  double master_stiffness_n_per_m = 0.0, master_damping_ns_per_m = 0.0, force_gain = 0.0,
         slave_stiffness_n_per_m = 0.0, forward_delay_ms = 0.0, backward_delay_ms = 0.0;
  double ramp_s = 0.5;
};

/// A request for `fields` (TUNE_* bits) with the form's values.
TuningRequest make_tuning_request(const TuningForm& form, std::uint32_t fields);

/// The master's hand in the slave world (MasterState.command_position_m) [m]; false until a
/// master state with a finite, non-zero hand arrived.
bool hand_world(const ViewerView& view, Eigen::Vector3d& hand_m);

/// The drive keys held this frame.
struct DriveKeys {
  bool right = false, left = false;         ///< world +x, -x
  bool up = false, down = false;            ///< world +y, -y
  bool page_up = false, page_down = false;  ///< world +z, -z
};
/// The world direction the held keys ask for (each axis -1, 0 or 1).
Eigen::Vector3d key_direction(const DriveKeys& keys);

/// The window's pointer this frame.
struct PointerInput {
  Eigen::Vector2f position_px = Eigen::Vector2f::Zero();  ///< window pixels, y down
  bool left_down = false;                                 ///< the left button is held
  bool left_clicked = false;                              ///< the left button went down this frame
  bool shift = false;           ///< shift is held (shift + left pans the camera)
  bool ui_wants_mouse = false;  ///< the pointer is over a UI window
};

class DriveInput {
 public:
  /// A press grabs the hand when it lands within this distance of the hand's ring [px].
  static constexpr float kGrabRadiusPx = 30.0f;

  explicit DriveInput(DriveTarget& target) : target_(target) {}

  /// A left press at `px` in the 3-D view of `layout`: grabs the master's hand when the press is
  /// within kGrabRadiusPx of where `camera` shows it. Returns true when a drag started.
  bool press(const Eigen::Vector2f& px, const ViewerView& view, const OrbitCamera& camera,
             const Layout& layout);
  /// Moves the drag under way to `px`.
  void move(const Eigen::Vector2f& px, const OrbitCamera& camera, const Layout& layout);
  void release() { target_.release(); }

  /// The window's pointer: a drag started with the mouse follows it until the button is let go;
  /// a left click (without shift, not over the UI, and not while `blocked` by another drag, the
  /// script's) may grab the hand. Returns true when the drive took the pointer this frame (the
  /// camera does not move then).
  bool pointer(const PointerInput& in, bool blocked, const ViewerView& view,
               const OrbitCamera& camera, const Layout& layout);
  /// Held keys move the target along `direction` (key_direction()) for `dt_s`.
  void keys(const Eigen::Vector3d& direction, double dt_s) { target_.nudge(direction, dt_s); }

  /// Sends the form's values for `fields` (TUNE_* bits).
  void send_tuning(std::uint32_t fields) {
    target_.send_tuning(make_tuning_request(form_, fields));
  }
  TuningForm& form() { return form_; }
  bool dragging() const { return target_.dragging(); }

 private:
  DriveTarget& target_;
  TuningForm form_;
  bool mouse_dragging_ = false;  ///< a drag started with the mouse
};

}  // namespace teleop::viewer
