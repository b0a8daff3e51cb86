#include "client/device/device_factory.hpp"

#include "common/config/config.hpp"
#ifdef TELEOP_HAVE_EVDEV
#include "client/device/evdev_device.hpp"
#endif
#ifdef TELEOP_WITH_VENDOR_SDK
#include "client/device/vendor/vendor_sdk_device.hpp"
#endif

namespace teleop::master {

bool is_hardware_device_name(const std::string& name) {
  return name.rfind("evdev:", 0) == 0 || name == "vendor" || name.rfind("vendor:", 0) == 0;
}

std::unique_ptr<HapticDevice> make_hardware_device(const std::string& name) {
  if (name.rfind("evdev:", 0) == 0) {
    const std::string path = name.substr(6);
    if (path.empty()) {
      throw config::ConfigError("--device '" + name +
                                "': give the event node, e.g. "
                                "evdev:/dev/input/event5");
    }
#ifdef TELEOP_HAVE_EVDEV
    EvdevDeviceParams p;
    p.path = path;
    return std::make_unique<EvdevDevice>(p);
#else
    throw config::ConfigError("--device '" + name +
                              "': built without libevdev "
                              "(install libevdev-dev and reconfigure)");
#endif
  }
  if (name == "vendor" || name.rfind("vendor:", 0) == 0) {
#ifdef TELEOP_WITH_VENDOR_SDK
    return make_vendor_sdk_device(name.size() > 7 ? name.substr(7) : std::string());
#else
    throw config::ConfigError("--device '" + name +
                              "': built without a vendor SDK "
                              "(configure with -DTELEOP_WITH_VENDOR_SDK=ON; docs/tools.md)");
#endif
  }
  return nullptr;
}

}  // namespace teleop::master
