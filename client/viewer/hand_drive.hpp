#pragma once
// HandDrive: the viewer as a haptic device driven by mouse and keyboard (teleop_viewer --drive).
// Pure math, no OpenGL and no DDS, so tests can drive it.
//
// The operator moves a target: dragging with the mouse moves it in the plane through the
// master's hand (MasterState.command_position_m) that faces the camera, by what the pointer
// moved in that plane; keys move it along the world axes at key_speed_mps. The slave-world
// motion becomes device motion through position_scale (slave metres per device metre, the
// master's workspace map; rotation identity). The target is kept inside a box of
// +-workspace_half_m around the start (a desk device's workspace). advance(dt) moves the handle
// toward the target at most max_speed_mps and max_accel_mps2 (a pointer jump becomes a quick,
// smooth motion, not a step of the slave's set point) and gives its velocity; that handle is what
// the viewer publishes as teleop/device_state at 1 kHz.
#include <Eigen/Core>

namespace teleop::viewer {

struct HandDriveParams {
  double position_scale = 1.0;     ///< slave metres per device metre (the master's alpha)
  double workspace_half_m = 0.15;  ///< target kept within +-this of the start, per axis [m]
  double max_speed_mps = 0.3;      ///< handle speed limit [m/s]
  double key_speed_mps = 0.05;     ///< speed of a held key [m/s]
  double max_accel_mps2 = 10.0;    ///< handle acceleration limit [m/s^2]
};

class HandDrive {
 public:
  explicit HandDrive(const HandDriveParams& params = {}) : p_(params) {}

  /// Starts a drag: `anchor_world_m` is the point that follows the pointer (the master's hand
  /// in the slave world), `view_dir` the camera's forward axis, the ray the pointer's.
  void grab(const Eigen::Vector3d& anchor_world_m, const Eigen::Vector3d& view_dir,
            const Eigen::Vector3d& ray_origin, const Eigen::Vector3d& ray_dir);
  /// Moves the dragged target with the pointer's ray. Ignored when not dragging.
  void drag(const Eigen::Vector3d& ray_origin, const Eigen::Vector3d& ray_dir);
  void release() { dragging_ = false; }
  bool dragging() const { return dragging_; }

  /// Moves the target by `direction` (world axes, e.g. (1,0,0) for a held right arrow) at the
  /// key speed for `dt_s`.
  void nudge(const Eigen::Vector3d& direction, double dt_s);
  /// Moves the target to `device_m` directly (clamped to the workspace).
  void set_target(const Eigen::Vector3d& device_m);

  /// The handle moves toward the target for `dt_s` (speed-limited).
  void advance(double dt_s);

  const Eigen::Vector3d& target_m() const { return target_; }      ///< device frame [m]
  const Eigen::Vector3d& position_m() const { return position_; }  ///< device frame [m]
  const Eigen::Vector3d& velocity_mps() const { return velocity_; }
  const HandDriveParams& params() const { return p_; }

 private:
  bool intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d, Eigen::Vector3d& hit) const;
  Eigen::Vector3d clamp(const Eigen::Vector3d& device_m) const;

  HandDriveParams p_;
  Eigen::Vector3d target_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d position_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d velocity_ = Eigen::Vector3d::Zero();
  bool dragging_ = false;
  Eigen::Vector3d plane_point_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d plane_normal_ = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d grab_hit_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d grab_target_ = Eigen::Vector3d::Zero();
};

}  // namespace teleop::viewer
