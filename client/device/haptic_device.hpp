#pragma once
// The haptic device layer: a device spec with units (as CHAI3D publishes one per device), one
// reading per haptic cycle, and a lifecycle (configure, activate, deactivate) in the manner of
// ros2_control hardware. Controllers clamp their gains and forces against the DeviceSpec.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>

namespace teleop::master {

/// What a device can do, with units on every field. Controllers clamp against it.
struct DeviceSpec {
  std::string name = "simulated-6dof";  ///< model name, for logs
  /// Workspace box, device frame: each coordinate of the handle lies in [min, max] [m].
  Eigen::Vector3d workspace_min_m = Eigen::Vector3d(-0.2, -0.2, -0.2);
  Eigen::Vector3d workspace_max_m = Eigen::Vector3d(0.2, 0.2, 0.2);
  double max_force_n = 10.0;              ///< peak force the actuators produce [N]
  double max_continuous_force_n = 6.0;    ///< force sustainable indefinitely [N]
  double max_torque_nm = 0.5;             ///< peak torque (0 if not actuated) [N m]
  double max_stiffness_n_per_m = 3000.0;  ///< largest stable virtual stiffness at 1 kHz [N/m]
  double max_damping_ns_per_m = 20.0;     ///< largest stable virtual damping [N s/m]
  int translational_dof = 3;              ///< actuated translational axes
  int rotational_dof = 3;                 ///< sensed rotational axes
  /// Largest rate of change of the commanded force [N/s]: the safety layer never changes the
  /// force written by more than this times the period in one cycle (no force steps), whatever
  /// the controller, a returning link or a re-homing asks. 1000 N/s is 1 N per 1 kHz cycle,
  /// the 10 N peak from zero in 10 ms. Contact with the default sphere loads at a few N/s and a
  /// 3000 N/m wall touched at 5 cm/s at 150 N/s; TDPA's damping at K = 3000 N/m and 100 ms
  /// needs more than 500 N/s to stay passive (tests/unit/client/control/passivity_test.cpp).
  double max_force_rate_n_per_s = 1000.0;

  /// True if `p` [m] lies inside the workspace box.
  bool inside_workspace(const Eigen::Vector3d& p) const {
    return (p.array() >= workspace_min_m.array()).all() &&
           (p.array() <= workspace_max_m.array()).all();
  }
};

/// One sample of the device handle, device frame.
struct DeviceReading {
  double time_s = 0.0;                                               ///< device clock [s]
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();              ///< handle position [m]
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();   ///< handle orientation
  Eigen::Vector3d linear_velocity_mps = Eigen::Vector3d::Zero();     ///< [m/s]
  Eigen::Vector3d angular_velocity_radps = Eigen::Vector3d::Zero();  ///< [rad/s]
  std::uint32_t buttons = 0;  ///< bit i set: button i pressed (bit 0 = clutch/enable)
  bool valid = false;         ///< false: no fresh data (device not active, or stale link)
};

/// Lifecycle state of a device (ros2_control-like).
enum class DeviceLifecycle : std::uint8_t { kUnconfigured = 0, kInactive = 1, kActive = 2 };

/// A haptic device. read() and write() are called once per haptic cycle from the real-time
/// loop and must not allocate; configure()/activate()/deactivate() are called outside it.
class HapticDevice {
 public:
  virtual ~HapticDevice() = default;

  /// Prepares the device (opens files/handles, allocates). @throws config::ConfigError on
  /// bad setup. Moves the state to kInactive.
  virtual void configure() = 0;
  /// Starts force output; afterwards read() returns valid samples. Moves to kActive.
  virtual void activate() = 0;
  /// Stops force output (zero force). Moves to kInactive.
  virtual void deactivate() = 0;
  /// Newest sample of the handle. Real-time safe.
  virtual DeviceReading read() = 0;
  /// Commands force [N] and torque [N m], device frame, held until the next write().
  /// The device saturates to its spec as a last line of defence. Real-time safe.
  virtual void write(const Eigen::Vector3d& force_n, const Eigen::Vector3d& torque_nm) = 0;
  /// Advances the device's own notion of time by dt [s]: simulated devices integrate their
  /// dynamics here, replay devices move along the record, external devices age their newest
  /// sample (staleness). Hardware with its own clock may ignore it. Real-time safe.
  virtual void advance(double dt_s) = 0;
  /// The device's capabilities.
  virtual const DeviceSpec& spec() const = 0;
  /// Current lifecycle state.
  virtual DeviceLifecycle state() const = 0;
};

/// Clamps `force_n` to a norm of at most `max_norm_n` [N] (direction kept). NaN gives zero.
inline Eigen::Vector3d saturate_norm(const Eigen::Vector3d& v, double max_norm) {
  if (!v.allFinite()) return Eigen::Vector3d::Zero();
  const double n = v.norm();
  return n > max_norm && n > 0.0 ? Eigen::Vector3d(v * (max_norm / n)) : v;
}

}  // namespace teleop::master
