#pragma once
// Devices named on the command line beyond the built-in simulated / replay / external ones:
//   evdev:/dev/input/eventN   a Linux force-feedback input device (evdev_device.hpp)
//   vendor[:ARG]              the vendor SDK driver (vendor/vendor_sdk_device.hpp), only when
//                             built with -DTELEOP_WITH_VENDOR_SDK=ON
#include <memory>
#include <string>

#include "client/device/haptic_device.hpp"

namespace teleop::master {

/// True if `name` names a device of this factory (whether or not it was built in).
bool is_hardware_device_name(const std::string& name);
/// The device for `name`, or nullptr if `name` is not a hardware device name.
/// @throws config::ConfigError if the name is malformed or the driver was not built in.
std::unique_ptr<HapticDevice> make_hardware_device(const std::string& name);

}  // namespace teleop::master
