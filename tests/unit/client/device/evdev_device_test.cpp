// The evdev force-feedback driver: its conversions (always), and the whole device against a
// virtual uinput device that reports axes and accepts force-feedback uploads (where the
// machine allows /dev/uinput; skipped with the reason otherwise). Also the vendor skeleton's
// lock-free servo exchange.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <thread>
#include <vector>

#include "client/device/device_factory.hpp"
#include "client/device/evdev_mapping.hpp"
#include "client/device/vendor/servo_exchange.hpp"
#include "common/config/config.hpp"

#ifdef TELEOP_HAVE_EVDEV
#include <dirent.h>
#include <fcntl.h>
#include <linux/uinput.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <mutex>

#include "client/device/evdev_device.hpp"
#endif

namespace teleop::master {
namespace {

using evdev::AxisRange;

TEST(EvdevMapping, AxisRangeMapsOntoTheWorkspaceBox) {
  const AxisRange a{true, 0, 1000};
  EXPECT_DOUBLE_EQ(evdev::axis_to_m(0, a, -0.1, 0.1), -0.1);
  EXPECT_DOUBLE_EQ(evdev::axis_to_m(1000, a, -0.1, 0.1), 0.1);
  EXPECT_NEAR(evdev::axis_to_m(500, a, -0.1, 0.1), 0.0, 1e-15);
  EXPECT_NEAR(evdev::axis_to_m(750, a, -0.1, 0.1), 0.05, 1e-15);
  EXPECT_DOUBLE_EQ(evdev::axis_to_m(2000, a, -0.1, 0.1), 0.1);  // beyond the range: clamped
  const AxisRange missing{};
  EXPECT_DOUBLE_EQ(evdev::axis_to_m(123, missing, -0.1, 0.3), 0.1);  // the centre
  const AxisRange centred{true, -32768, 32767};
  EXPECT_NEAR(evdev::axis_to_m(-32768, centred, -0.2, 0.2), -0.2, 1e-12);
}

TEST(EvdevMapping, ForceToConstantEffectFollowsTheLinuxDirectionConvention) {
  // 0x0000 towards +y, 0x4000 towards -x, 0x8000 towards -y, 0xC000 towards +x
  auto e = evdev::force_to_effect(Eigen::Vector3d(0, 1, 0), 2.0);
  EXPECT_EQ(e.direction, 0x0000);
  EXPECT_EQ(e.level, std::lround(0.5 * 0x7fff));
  EXPECT_EQ(evdev::force_to_effect(Eigen::Vector3d(-1, 0, 0), 2.0).direction, 0x4000);
  EXPECT_EQ(evdev::force_to_effect(Eigen::Vector3d(0, -1, 0), 2.0).direction, 0x8000);
  EXPECT_EQ(evdev::force_to_effect(Eigen::Vector3d(1, 0, 0), 2.0).direction, 0xC000);
  // saturates at full scale; z is not rendered; NaN gives zero
  EXPECT_EQ(evdev::force_to_effect(Eigen::Vector3d(0, 5, 0), 2.0).level, 0x7fff);
  EXPECT_EQ(evdev::force_to_effect(Eigen::Vector3d(0, 0, 1), 2.0).level, 0);
  EXPECT_EQ(evdev::force_to_effect(Eigen::Vector3d(NAN, 0, 0), 2.0).level, 0);
  // round trip within the quantisation
  for (const Eigen::Vector3d& f : {Eigen::Vector3d(0.3, -1.2, 0), Eigen::Vector3d(-1.5, -0.4, 0),
                                   Eigen::Vector3d(0.7, 0.7, 0)}) {
    const Eigen::Vector3d back = evdev::effect_to_force(evdev::force_to_effect(f, 2.0), 2.0);
    EXPECT_NEAR((back - f).norm(), 0.0, 1e-3) << f.transpose() << " -> " << back.transpose();
  }
}

TEST(EvdevMapping, EffectEndsByItselfWithAFadeAtTheRateBound) {
  // 1.5 N of 2 N full scale at a 100 N/s bound: fades over 15 ms after the hold
  const evdev::ConstantForce e = evdev::force_to_effect(Eigen::Vector3d(0, 1.5, 0), 2.0);
  const ff_effect f = evdev::make_effect(e, 7, 2.0, 100.0);
  EXPECT_EQ(f.type, FF_CONSTANT);
  EXPECT_EQ(f.id, 7);
  EXPECT_EQ(f.u.constant.level, e.level);
  EXPECT_EQ(f.direction, e.direction);
  EXPECT_EQ(f.u.constant.envelope.fade_length, 15);
  EXPECT_EQ(f.u.constant.envelope.fade_level, 0);
  EXPECT_EQ(f.replay.length, evdev::kEffectHoldMs + 15);  // finite: never 0 (infinite)
  // the driver refreshes well before the effect would start fading
  EXPECT_LT(evdev::kEffectRefreshMs, evdev::kEffectHoldMs);
  // a new effect (id -1), zero force: plays the hold only
  const ff_effect zero = evdev::make_effect(evdev::ConstantForce{}, -1, 2.0, 100.0);
  EXPECT_EQ(zero.id, -1);
  EXPECT_EQ(zero.u.constant.envelope.fade_length, 0);
  EXPECT_EQ(zero.replay.length, evdev::kEffectHoldMs);
  // full scale at the default 1000 N/s: 2 ms; no bound: at least 1 ms; a slow bound: at most 10 s
  const evdev::ConstantForce full = evdev::force_to_effect(Eigen::Vector3d(0, 9, 0), 2.0);
  EXPECT_EQ(evdev::effect_fade_ms(full, 2.0, 1000.0), 2);
  EXPECT_EQ(evdev::effect_fade_ms(full, 2.0, 0.0), 1);
  EXPECT_EQ(evdev::effect_fade_ms(full, 2.0, 1e-6), 10000);
  EXPECT_GT(evdev::make_effect(full, 1, 2.0, 1e-6).replay.length, 10000);
}

TEST(DeviceFactory, NamesAndErrors) {
  EXPECT_TRUE(is_hardware_device_name("evdev:/dev/input/event3"));
  EXPECT_TRUE(is_hardware_device_name("vendor"));
  EXPECT_FALSE(is_hardware_device_name("simulated"));
  EXPECT_EQ(make_hardware_device("simulated"), nullptr);
  EXPECT_THROW(make_hardware_device("evdev:"), config::ConfigError);
#ifndef TELEOP_WITH_VENDOR_SDK
  EXPECT_THROW(make_hardware_device("vendor"), config::ConfigError);
#endif
#ifdef TELEOP_HAVE_EVDEV
  auto d = make_hardware_device("evdev:/nonexistent/event99");
  ASSERT_NE(d, nullptr);
  try {
    d->configure();
    FAIL() << "configure() opened a file that does not exist";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/event99"), std::string::npos) << e.what();
  }
#endif
}

TEST(ServoExchange, ReaderNeverSeesATornValue) {
  vendor::Seqlock<vendor::ServoReading> lock;
  vendor::ServoReading r;
  EXPECT_EQ(lock.load(r), 0u);
  std::atomic<bool> done{false};
  std::thread writer([&] {
    vendor::ServoReading w;
    for (int i = 1; i <= 200000; ++i) {
      w.time_s = i;
      for (double& p : w.position_m) p = i;
      lock.store(w);
    }
    done = true;
  });
  std::uint64_t torn = 0, reads = 0;
  while (!done.load()) {
    lock.load(r);
    ++reads;
    if (r.position_m[0] != r.time_s || r.position_m[2] != r.time_s) ++torn;
  }
  writer.join();
  EXPECT_EQ(torn, 0u) << reads << " reads";
  EXPECT_EQ(lock.load(r), 200000u);
  EXPECT_EQ(r.time_s, 200000.0);
}

#ifdef TELEOP_HAVE_EVDEV
/// A virtual joystick made with uinput: ABS_X/ABS_Y in [0, 1000], one button, FF_CONSTANT.
/// A thread answers the kernel's effect uploads and records them.
class VirtualJoystick {
 public:
  bool create(std::string& why) {
    fd_ = ::open("/dev/uinput", O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd_ < 0) {
      why = std::string("cannot open /dev/uinput: ") + std::strerror(errno) +
            " (no uinput module or no permission in this environment)";
      return false;
    }
    bool ok = ioctl(fd_, UI_SET_EVBIT, EV_ABS) == 0 && ioctl(fd_, UI_SET_EVBIT, EV_KEY) == 0 &&
              ioctl(fd_, UI_SET_EVBIT, EV_FF) == 0 && ioctl(fd_, UI_SET_KEYBIT, BTN_TRIGGER) == 0 &&
              ioctl(fd_, UI_SET_FFBIT, FF_CONSTANT) == 0;
    for (int axis : {ABS_X, ABS_Y}) {
      uinput_abs_setup a{};
      a.code = static_cast<std::uint16_t>(axis);
      a.absinfo.minimum = 0;
      a.absinfo.maximum = 1000;
      ok = ok && ioctl(fd_, UI_SET_ABSBIT, axis) == 0 && ioctl(fd_, UI_ABS_SETUP, &a) == 0;
    }
    uinput_setup s{};
    s.id.bustype = BUS_VIRTUAL;
    s.id.vendor = 0x1234;
    s.id.product = 0x5678;
    std::snprintf(s.name, sizeof(s.name), "teleop test joystick %d", getpid());
    s.ff_effects_max = 4;
    ok = ok && ioctl(fd_, UI_DEV_SETUP, &s) == 0 && ioctl(fd_, UI_DEV_CREATE) == 0;
    if (!ok) {
      why = std::string("uinput refused the virtual device: ") + std::strerror(errno);
      return false;
    }
    char sys[64] = {};
    if (ioctl(fd_, UI_GET_SYSNAME(sizeof(sys)), sys) < 0) {
      why = "UI_GET_SYSNAME failed";
      return false;
    }
    const std::string dir = std::string("/sys/devices/virtual/input/") + sys;
    for (int attempt = 0; attempt < 100 && node_.empty(); ++attempt) {
      if (DIR* d = opendir(dir.c_str())) {
        while (dirent* e = readdir(d)) {
          if (std::strncmp(e->d_name, "event", 5) == 0)
            node_ = std::string("/dev/input/") + e->d_name;
        }
        closedir(d);
      }
      if (node_.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    for (int attempt = 0;
         attempt < 100 && !node_.empty() && access(node_.c_str(), R_OK | W_OK) != 0; ++attempt) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));  // udev creates the node
    }
    if (node_.empty() || access(node_.c_str(), R_OK | W_OK) != 0) {
      why = "the virtual device has no accessible /dev/input/event node (no udev/devtmpfs here)";
      return false;
    }
    thread_ = std::thread([this] { serve(); });
    return true;
  }
  ~VirtualJoystick() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    if (fd_ >= 0) {
      ioctl(fd_, UI_DEV_DESTROY);
      ::close(fd_);
    }
  }
  const std::string& node() const { return node_; }
  void emit(int type, int code, int value) {
    input_event ev{};
    ev.type = static_cast<std::uint16_t>(type);
    ev.code = static_cast<std::uint16_t>(code);
    ev.value = value;
    [[maybe_unused]] const ssize_t n = ::write(fd_, &ev, sizeof(ev));
  }
  void move(int x, int y, bool button) {
    emit(EV_ABS, ABS_X, x);
    emit(EV_ABS, ABS_Y, y);
    emit(EV_KEY, BTN_TRIGGER, button ? 1 : 0);
    emit(EV_SYN, SYN_REPORT, 0);
  }
  std::vector<ff_effect> uploads() {
    std::lock_guard<std::mutex> l(m_);
    return uploads_;
  }
  int plays() const { return plays_.load(); }

 private:
  void serve() {
    while (!stop_) {
      input_event ev{};
      if (::read(fd_, &ev, sizeof(ev)) != static_cast<ssize_t>(sizeof(ev))) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        continue;
      }
      if (ev.type == EV_UINPUT && ev.code == UI_FF_UPLOAD) {
        uinput_ff_upload up{};
        up.request_id = static_cast<std::uint32_t>(ev.value);
        if (ioctl(fd_, UI_BEGIN_FF_UPLOAD, &up) == 0) {
          {
            std::lock_guard<std::mutex> l(m_);
            uploads_.push_back(up.effect);
          }
          up.retval = 0;
          ioctl(fd_, UI_END_FF_UPLOAD, &up);
        }
      } else if (ev.type == EV_UINPUT && ev.code == UI_FF_ERASE) {
        uinput_ff_erase er{};
        er.request_id = static_cast<std::uint32_t>(ev.value);
        if (ioctl(fd_, UI_BEGIN_FF_ERASE, &er) == 0) {
          er.retval = 0;
          ioctl(fd_, UI_END_FF_ERASE, &er);
        }
      } else if (ev.type == EV_FF && ev.value == 1) {
        ++plays_;
      }
    }
  }
  int fd_ = -1;
  std::string node_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::mutex m_;
  std::vector<ff_effect> uploads_;
  std::atomic<int> plays_{0};
};

TEST(EvdevDevice, ReadsAxesAndUploadsConstantForceOnAVirtualUinputDevice) {
  VirtualJoystick js;
  std::string why;
  if (!js.create(why)) {
    std::printf("[  SKIPPED ] no virtual uinput device: %s\n", why.c_str());
    GTEST_SKIP() << why;
  }
  EvdevDeviceParams p;
  p.path = js.node();
  EvdevDevice dev(p);
  dev.configure();
  ASSERT_TRUE(dev.has_force_feedback());
  EXPECT_EQ(dev.spec().translational_dof, 2);
  dev.activate();
  EXPECT_EQ(dev.state(), DeviceLifecycle::kActive);
  js.move(750, 250, true);
  DeviceReading r;
  for (int i = 0; i < 200; ++i) {  // the events reach the node asynchronously
    dev.advance(0.001);
    r = dev.read();
    if (std::abs(r.position_m.x() - 0.05) < 1e-9) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_TRUE(r.valid);
  EXPECT_NEAR(r.position_m.x(), 0.05, 1e-9);  // 750 of [0, 1000] on [-0.1, 0.1]
  EXPECT_NEAR(r.position_m.y(), -0.05, 1e-9);
  EXPECT_NEAR(r.position_m.z(), 0.0, 1e-12);  // no ABS_Z: the centre
  EXPECT_EQ(r.buttons & 1u, 1u);
  // a force towards +x at half the peak becomes a constant effect "right", level 0x3fff
  dev.write(Eigen::Vector3d(1.0, 0.0, 0.3), Eigen::Vector3d::Zero());
  const auto uploads_after_write = dev.uploads();
  dev.write(Eigen::Vector3d(1.0, 0.0, 0.3), Eigen::Vector3d::Zero());  // same: no upload
  EXPECT_EQ(dev.uploads(), uploads_after_write);
  const auto ups = js.uploads();
  ASSERT_GE(ups.size(), 2u);
  EXPECT_EQ(ups.back().type, FF_CONSTANT);
  EXPECT_EQ(ups.back().direction, 0xC000);
  EXPECT_EQ(ups.back().u.constant.level, std::lround(0.5 * 0x7fff));
  EXPECT_GT(ups.back().replay.length, 0);  // finite: ends by itself without refreshes
  EXPECT_GE(js.plays(), 1);
  dev.deactivate();
  EXPECT_EQ(js.uploads().back().u.constant.level, 0);  // zero force when deactivated
}
#endif

}  // namespace
}  // namespace teleop::master
