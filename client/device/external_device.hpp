#pragma once
// ExternalDevice: a haptic device driven by another process (a hardware driver), reached
// through some transport (the master node uses DDS topics teleop/device_state and
// teleop/device_command, idl/Device.idl). This class is transport-agnostic:
//   - the node takes the newest DeviceState sample from its reader and hands it over with
//     on_sample() (same thread as the haptic loop);
//   - read() returns it as a DeviceReading, invalid once it is older than the staleness
//     timeout (age measured by advance(dt), i.e. the haptic loop's own clock);
//   - write() stores the force; next_command() gives the node the DeviceCommand to publish.
//     A stale link or an inactive device always commands zero force with enable = false.
// See client/device/device_idl.hpp for the conversions to and from the IDL types.
#include <cstdint>

#include "client/device/haptic_device.hpp"

namespace teleop::master {

/// Transport-neutral copy of teleop::DeviceState (idl/Device.idl).
struct ExternalDeviceSample {
  std::uint64_t seq = 0;                                             ///< driver sample counter
  std::int64_t time_ns = 0;                                          ///< driver clock [ns]
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();              ///< [m]
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();   ///< unit quaternion
  Eigen::Vector3d linear_velocity_mps = Eigen::Vector3d::Zero();     ///< [m/s]
  Eigen::Vector3d angular_velocity_radps = Eigen::Vector3d::Zero();  ///< [rad/s]
  std::uint32_t buttons = 0;                                         ///< button bits
  bool engaged = false;                                              ///< driver ready
};

/// Transport-neutral copy of teleop::DeviceCommand (idl/Device.idl).
struct ExternalDeviceCommand {
  std::uint64_t seq = 0;                                ///< command counter
  std::uint64_t state_seq = 0;                          ///< newest sample seq used
  Eigen::Vector3d force_n = Eigen::Vector3d::Zero();    ///< [N]
  Eigen::Vector3d torque_nm = Eigen::Vector3d::Zero();  ///< [N m]
  bool enable = false;                                  ///< false: zero force
};

/// Adapter from the newest external sample to the HapticDevice interface.
class ExternalDevice final : public HapticDevice {
 public:
  /// `staleness_timeout_s` [s]: a sample older than this is not valid any more.
  explicit ExternalDevice(DeviceSpec spec, double staleness_timeout_s = 0.01);

  void configure() override;
  void activate() override;
  void deactivate() override;
  DeviceReading read() override;
  void write(const Eigen::Vector3d& force_n, const Eigen::Vector3d& torque_nm) override;
  void advance(double dt_s) override;
  const DeviceSpec& spec() const override { return spec_; }
  DeviceLifecycle state() const override { return state_; }

  /// Hands over the newest sample from the transport. Older or repeated seqs are ignored
  /// (returns false) while the held sample is fresh; once it is stale any seq is accepted
  /// (a restarted driver counts from 0 again). Real-time safe.
  bool on_sample(const ExternalDeviceSample& sample);
  /// The command to publish now (force zero and enable false when stale or inactive).
  ExternalDeviceCommand next_command();
  /// True when a sample newer than the timeout is held.
  bool fresh() const { return have_sample_ && age_s_ <= timeout_s_; }
  /// Age of the newest sample [s] (time advanced since it arrived).
  double age_s() const { return age_s_; }
  /// Times the link went stale (fresh -> stale transitions).
  std::uint64_t stale_events() const { return stale_events_; }

 private:
  DeviceSpec spec_;
  double timeout_s_;
  DeviceLifecycle state_ = DeviceLifecycle::kUnconfigured;
  ExternalDeviceSample newest_;
  bool have_sample_ = false;
  bool was_fresh_ = false;
  double age_s_ = 0.0;
  double clock_s_ = 0.0;
  std::uint64_t stale_events_ = 0;
  std::uint64_t command_seq_ = 0;
  Eigen::Vector3d force_n_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d torque_nm_ = Eigen::Vector3d::Zero();
};

}  // namespace teleop::master
