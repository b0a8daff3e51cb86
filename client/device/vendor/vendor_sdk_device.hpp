#pragma once
// Driver skeleton for a commercial haptic device through its vendor SDK (3D Systems
// OpenHaptics "HD" API; Force Dimension's DHD API has the same shape). Built only with
// -DTELEOP_WITH_VENDOR_SDK=ON, which finds the SDK (client/CMakeLists.txt); selected with
// `teleop_master --device vendor[:DEVICE_NAME]`. docs/tools.md walks through adapting it.
//
// Shape of every such driver:
//   configure()  open the device (hdInitDevice / dhdOpen), read what it declares into the
//                DeviceSpec: workspace box, peak and continuous force, stiffness and damping it
//                renders stably (HD_USABLE_WORKSPACE_*, HD_NOMINAL_MAX_FORCE,
//                HD_NOMINAL_MAX_CONTINUOUS_FORCE, HD_NOMINAL_MAX_STIFFNESS,
//                HD_NOMINAL_MAX_DAMPING). The master clamps its gains and forces against it
//                (BilateralController::configure, SafetyFilter).
//   activate()   register the servo callback (hdScheduleAsynchronous) and start the SDK's
//                1 kHz scheduler; enable forces.
//   servo tick   (SDK thread, 1 kHz) begin frame; read position [mm -> m], velocity, transform,
//                buttons; publish them to the ServoExchange; take the newest force, saturate it
//                to the spec, write it (hdSetDoublev(HD_CURRENT_FORCE)); end frame; an SDK error
//                zeroes the force and flags a fault. The force it writes changes by at most the
//                spec's rate bound per tick, and when the haptic loop has written nothing for
//                kServoStaleTicks ticks (its loop stalled: the servo thread runs on) it fades to
//                zero at that bound instead of holding the last force.
//   read()/write() (haptic loop) exchange with the servo tick through seqlocks: no locks, no
//                allocation, no SDK call on the master's thread.
//   deactivate() zero the force, unschedule the callback, stop the scheduler.
#include <cstdint>
#include <memory>
#include <string>

#include "client/device/haptic_device.hpp"
#include "client/device/vendor/servo_exchange.hpp"

namespace teleop::master {

/// Servo ticks (1 kHz) without a new force from the haptic loop after which the servo thread
/// fades the force out.
constexpr int kServoStaleTicks = 50;
/// The SDK scheduler's period [s].
constexpr double kServoPeriodS = 1e-3;

class VendorSdkDevice final : public HapticDevice {
 public:
  explicit VendorSdkDevice(std::string device_name);
  ~VendorSdkDevice() override;

  void configure() override;
  void activate() override;
  void deactivate() override;
  DeviceReading read() override;
  void write(const Eigen::Vector3d& force_n, const Eigen::Vector3d& torque_nm) override;
  void advance(double dt_s) override;
  const DeviceSpec& spec() const override { return spec_; }
  DeviceLifecycle state() const override { return state_; }

  /// One servo tick; called by the SDK's scheduler thread (public for the C callback).
  bool servo_tick();

 private:
  std::string device_name_;
  DeviceSpec spec_;
  DeviceLifecycle state_ = DeviceLifecycle::kUnconfigured;
  vendor::ServoExchange exchange_;
  unsigned long handle_ = 0;    // HHD
  unsigned long callback_ = 0;  // HDSchedulerHandle
  double time_s_ = 0.0;
  // the servo thread's own (no other thread touches them)
  std::uint32_t servo_seen_ = 0;                             // commands stored when it last looked
  int servo_stale_ticks_ = 0;                                // ticks since a new command
  Eigen::Vector3d servo_force_n_ = Eigen::Vector3d::Zero();  // what it wrote last [N]
};

/// Factory used by device_factory.cpp.
std::unique_ptr<HapticDevice> make_vendor_sdk_device(const std::string& device_name);

}  // namespace teleop::master
