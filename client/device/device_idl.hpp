#pragma once
// Conversions between the transport-neutral ExternalDevice samples and the DDS types of
// idl/Device.idl (teleop::DeviceState, teleop::DeviceCommand). Header-only; include it only
// where the generated types are wanted (the master node).
#include "client/device/external_device.hpp"
#include "teleop/idl/Device.h"

namespace teleop::master {

/// teleop::DeviceState (DDS) -> ExternalDeviceSample.
inline ExternalDeviceSample from_idl(const teleop::DeviceState& m) {
  ExternalDeviceSample s;
  s.seq = m.seq();
  s.time_ns = m.time_ns();
  s.position_m = Eigen::Vector3d(m.position_m()[0], m.position_m()[1], m.position_m()[2]);
  s.orientation = Eigen::Quaterniond(m.orientation_wxyz()[0], m.orientation_wxyz()[1],
                                     m.orientation_wxyz()[2], m.orientation_wxyz()[3]);
  if (s.orientation.norm() > 1e-9) {
    s.orientation.normalize();
  } else {
    s.orientation = Eigen::Quaterniond::Identity();
  }
  for (int i = 0; i < 3; ++i) {
    s.linear_velocity_mps[i] = m.linear_velocity_mps()[static_cast<std::size_t>(i)];
    s.angular_velocity_radps[i] = m.angular_velocity_radps()[static_cast<std::size_t>(i)];
  }
  s.buttons = m.buttons();
  s.engaged = m.engaged();
  return s;
}

/// ExternalDeviceCommand -> teleop::DeviceCommand (DDS); `time_ns` is the send time [ns].
inline teleop::DeviceCommand to_idl(const ExternalDeviceCommand& c, std::int64_t time_ns) {
  teleop::DeviceCommand m;
  m.seq(c.seq);
  m.time_ns(time_ns);
  m.state_seq(c.state_seq);
  for (std::size_t i = 0; i < 3; ++i) {
    m.force_n()[i] = c.force_n[static_cast<int>(i)];
    m.torque_nm()[i] = c.torque_nm[static_cast<int>(i)];
  }
  m.enable(c.enable);
  return m;
}

}  // namespace teleop::master
