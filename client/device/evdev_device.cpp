#include "client/device/evdev_device.hpp"

#include <fcntl.h>
#include <libevdev/libevdev.h>
#include <linux/input.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <iostream>

#include "common/config/config.hpp"
#include "common/util/clock.hpp"

namespace teleop::master {

namespace {
constexpr int kAxes[3] = {ABS_X, ABS_Y, ABS_Z};
}

EvdevDevice::EvdevDevice(EvdevDeviceParams params) : params_(std::move(params)) {}

EvdevDevice::~EvdevDevice() {
  if (state_ == DeviceLifecycle::kActive) deactivate();
  if (dev_) libevdev_free(dev_);
  if (fd_ >= 0) ::close(fd_);
}

void EvdevDevice::configure() {
  if (fd_ >= 0) return;
  fd_ = ::open(params_.path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) {
    throw config::ConfigError("--device evdev:" + params_.path +
                              ": cannot open: " + std::strerror(errno) +
                              " (an event device under /dev/input; read/write access needed, "
                              "e.g. the input group)");
  }
  const int rc = libevdev_new_from_fd(fd_, &dev_);
  if (rc < 0) {
    throw config::ConfigError("--device evdev:" + params_.path +
                              ": not an evdev device: " + std::strerror(-rc));
  }
  for (int i = 0; i < 3; ++i) {
    const input_absinfo* a = libevdev_get_abs_info(dev_, static_cast<unsigned>(kAxes[i]));
    axes_[i].present = a != nullptr && libevdev_has_event_code(dev_, EV_ABS, kAxes[i]);
    if (axes_[i].present) {
      axes_[i].minimum = a->minimum;
      axes_[i].maximum = a->maximum;
    }
  }
  if (!axes_[0].present || !axes_[1].present) {
    throw config::ConfigError("--device evdev:" + params_.path + " ('" +
                              std::string(libevdev_get_name(dev_)) +
                              "') has no absolute X and Y axes");
  }
  button_count_ = 0;
  for (unsigned code = BTN_MISC; code < BTN_GEAR_UP + 1 && button_count_ < 32; ++code) {
    if (libevdev_has_event_code(dev_, EV_KEY, code))
      button_codes_[button_count_++] = static_cast<int>(code);
  }
  has_ff_ = libevdev_has_event_code(dev_, EV_FF, FF_CONSTANT);
  full_scale_n_ = params_.spec.max_force_n;
  if (!has_ff_) {
    std::cerr << "teleop_master: " << params_.path << " ('" << libevdev_get_name(dev_)
              << "') has no constant-force effect: position only, no force rendered\n";
    params_.spec.max_force_n = 0.0;
    params_.spec.max_continuous_force_n = 0.0;
  }
  if (params_.spec.name == "evdev")
    params_.spec.name = std::string("evdev: ") + libevdev_get_name(dev_);
  drain_events();
  state_ = DeviceLifecycle::kInactive;
}

bool EvdevDevice::upload(const evdev::ConstantForce& e) {
  ff_effect effect =
      evdev::make_effect(e, effect_id_, full_scale_n_, params_.spec.max_force_rate_n_per_s);
  if (ioctl(fd_, EVIOCSFF, &effect) < 0) return false;
  effect_id_ = effect.id;
  current_ = e;
  refreshed_ns_ = now_ns();
  ++uploads_;
  return true;
}

bool EvdevDevice::play() {
  input_event play{};
  play.type = EV_FF;
  play.code = static_cast<std::uint16_t>(effect_id_);
  play.value = 1;
  return ::write(fd_, &play, sizeof(play)) == static_cast<ssize_t>(sizeof(play));
}

void EvdevDevice::activate() {
  if (state_ == DeviceLifecycle::kUnconfigured) configure();
  if (state_ == DeviceLifecycle::kActive) return;
  if (has_ff_) {
    effect_id_ = -1;
    if (!upload(evdev::ConstantForce{})) {
      throw config::ConfigError(
          "--device evdev:" + params_.path +
          ": the constant-force effect upload failed: " + std::strerror(errno));
    }
    if (!play()) {
      throw config::ConfigError("--device evdev:" + params_.path +
                                ": cannot start the effect: " + std::strerror(errno));
    }
  }
  have_prev_ = false;
  state_ = DeviceLifecycle::kActive;
}

void EvdevDevice::deactivate() {
  if (state_ != DeviceLifecycle::kActive) return;
  if (has_ff_ && effect_id_ >= 0) {
    upload(evdev::ConstantForce{});
    input_event stop{};
    stop.type = EV_FF;
    stop.code = static_cast<std::uint16_t>(effect_id_);
    stop.value = 0;
    [[maybe_unused]] const ssize_t n = ::write(fd_, &stop, sizeof(stop));
    ioctl(fd_, EVIOCRMFF, effect_id_);
    effect_id_ = -1;
  }
  state_ = DeviceLifecycle::kInactive;
}

void EvdevDevice::drain_events() {
  input_event ev;
  int flag = LIBEVDEV_READ_FLAG_NORMAL;
  while (true) {
    const int rc = libevdev_next_event(dev_, flag, &ev);
    if (rc == LIBEVDEV_READ_STATUS_SYNC) {
      flag = LIBEVDEV_READ_FLAG_SYNC;  // events were dropped: resynchronise the state
    } else if (rc == LIBEVDEV_READ_STATUS_SUCCESS) {
      continue;
    } else if (rc == -EAGAIN && flag == LIBEVDEV_READ_FLAG_SYNC) {
      flag = LIBEVDEV_READ_FLAG_NORMAL;
    } else {
      break;  // -EAGAIN: nothing more; other errors: keep the last state
    }
  }
}

Eigen::Vector3d EvdevDevice::position_now() const {
  Eigen::Vector3d x;
  for (int i = 0; i < 3; ++i) {
    const int v = axes_[i].present
                      ? libevdev_get_event_value(dev_, EV_ABS, static_cast<unsigned>(kAxes[i]))
                      : 0;
    x[i] = evdev::axis_to_m(v, axes_[i], params_.spec.workspace_min_m[i],
                            params_.spec.workspace_max_m[i]);
  }
  return x;
}

DeviceReading EvdevDevice::read() {
  DeviceReading r;
  if (state_ != DeviceLifecycle::kActive) return r;
  drain_events();
  r.time_s = time_s_;
  r.position_m = position_now();
  r.linear_velocity_mps = v_;
  for (int b = 0; b < button_count_; ++b) {
    if (libevdev_get_event_value(dev_, EV_KEY, static_cast<unsigned>(button_codes_[b]))) {
      r.buttons |= 1u << b;
    }
  }
  r.valid = true;
  return r;
}

void EvdevDevice::write(const Eigen::Vector3d& force_n, const Eigen::Vector3d&) {
  if (state_ != DeviceLifecycle::kActive || !has_ff_) return;
  const Eigen::Vector3d f = saturate_norm(force_n, params_.spec.max_force_n);
  const evdev::ConstantForce e = evdev::force_to_effect(f, full_scale_n_);
  // a changed effect, or one about to expire: re-upload and restart it (an effect that ended
  // because the master stalled plays again only when restarted)
  // (the wall clock: the device's time does not advance while the master homes)
  if (e != current_ || now_ns() - refreshed_ns_ >= evdev::kEffectRefreshMs * 1000000LL) {
    if (upload(e)) play();
  }
}

void EvdevDevice::advance(double dt_s) {
  time_s_ += dt_s;
  if (state_ != DeviceLifecycle::kActive || dt_s <= 0.0) return;
  drain_events();
  const Eigen::Vector3d x = position_now();
  if (have_prev_) {
    const double a = std::min(1.0, 2.0 * M_PI * params_.velocity_cutoff_hz * dt_s);
    v_ += a * ((x - x_prev_) / dt_s - v_);
  }
  x_prev_ = x;
  have_prev_ = true;
}

}  // namespace teleop::master
