#pragma once
// A Linux force-feedback input device (joystick, wheel, pad) as a HapticDevice, through evdev
// (libevdev): absolute axes -> handle position, a constant-force effect <- force. Selected with
// `teleop_master --device evdev:/dev/input/eventN`. The conversions and their scale are in
// evdev_mapping.hpp; docs/tools.md lists what such a device can and cannot render.
//
// Lifecycle: configure() opens the node (O_RDWR, non-blocking), checks ABS_X and ABS_Y and
// reads the axis ranges; activate() uploads a constant-force effect and plays it (if the device
// has FF_CONSTANT; without it the spec declares max_force_n = 0 and the master renders no
// force); deactivate() stops and removes the effect. read() drains pending events without
// blocking; write() re-uploads and restarts the effect when its quantised level or direction
// changed or its last refresh is evdev::kEffectRefreshMs old: each upload plays a finite time
// and fades at the device's force-rate bound (evdev_mapping.hpp), so a stalled master's force
// ends by itself.
// Neither allocates.
#include <cstdint>
#include <string>

#include "client/device/evdev_mapping.hpp"
#include "client/device/haptic_device.hpp"

struct libevdev;

namespace teleop::master {

struct EvdevDeviceParams {
  std::string path;  ///< /dev/input/eventN
  /// Limits. The default is a small desk joystick: +-0.1 m box, 2 N peak (full-scale level),
  /// 300 N/m stiffness; set these from the device's data sheet.
  DeviceSpec spec = [] {
    DeviceSpec s;
    s.name = "evdev";
    s.workspace_min_m = Eigen::Vector3d(-0.1, -0.1, -0.1);
    s.workspace_max_m = Eigen::Vector3d(0.1, 0.1, 0.1);
    s.max_force_n = 2.0;
    s.max_continuous_force_n = 1.0;
    s.max_torque_nm = 0.0;
    s.max_stiffness_n_per_m = 300.0;
    s.max_damping_ns_per_m = 5.0;
    s.translational_dof = 2;
    s.rotational_dof = 0;
    return s;
  }();
  double velocity_cutoff_hz = 30.0;  ///< low-pass of the finite-difference velocity [Hz]
};

class EvdevDevice final : public HapticDevice {
 public:
  explicit EvdevDevice(EvdevDeviceParams params);
  ~EvdevDevice() override;
  EvdevDevice(const EvdevDevice&) = delete;
  EvdevDevice& operator=(const EvdevDevice&) = delete;

  void configure() override;
  void activate() override;
  void deactivate() override;
  DeviceReading read() override;
  void write(const Eigen::Vector3d& force_n, const Eigen::Vector3d& torque_nm) override;
  void advance(double dt_s) override;
  const DeviceSpec& spec() const override { return params_.spec; }
  DeviceLifecycle state() const override { return state_; }

  /// True if the device accepted a constant-force effect.
  bool has_force_feedback() const { return has_ff_; }
  /// The effect last uploaded.
  evdev::ConstantForce effect() const { return current_; }
  /// Effect uploads so far (activate + changes).
  unsigned long uploads() const { return uploads_; }

 private:
  void drain_events();
  bool upload(const evdev::ConstantForce& e);
  /// Starts (or restarts) the uploaded effect; false when the device refused the write.
  bool play();
  Eigen::Vector3d position_now() const;

  EvdevDeviceParams params_;
  DeviceLifecycle state_ = DeviceLifecycle::kUnconfigured;
  int fd_ = -1;
  libevdev* dev_ = nullptr;
  evdev::AxisRange axes_[3];
  int button_codes_[32] = {};
  int button_count_ = 0;
  bool has_ff_ = false;
  int effect_id_ = -1;
  evdev::ConstantForce current_;
  unsigned long uploads_ = 0;
  double time_s_ = 0.0;
  std::int64_t refreshed_ns_ = 0;  ///< steady clock at the last upload [ns]
  Eigen::Vector3d x_prev_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_ = Eigen::Vector3d::Zero();
  bool have_prev_ = false;
  double full_scale_n_ = 0.0;  ///< force at level 0x7fff
};

}  // namespace teleop::master
