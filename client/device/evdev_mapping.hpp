#pragma once
// Pure conversions of the evdev driver (evdev_device.hpp), unit-tested without a device.
//
// Position: each absolute axis (ABS_X, ABS_Y, ABS_Z) maps linearly from its range
// [minimum, maximum] (reported by the kernel) onto the DeviceSpec workspace box of the same
// axis: x = workspace_min + (value - minimum) * (workspace_max - workspace_min) /
// (maximum - minimum), i.e. a scale of (workspace span / axis span) metres per count; an axis
// the device lacks reads the centre of the box. Device frame = the axes' frame: +x where
// ABS_X grows (right), +y where ABS_Y grows (towards the user on a joystick), +z where ABS_Z
// grows.
//
// Force: a Linux constant-force effect is planar: a signed 16-bit level and a direction
// angle, encoded 0x0000 = force towards +y ("down"), 0x4000 = towards -x ("left"), 0x8000 =
// towards -y ("up"), 0xC000 = towards +x ("right") (linux/input.h). The x-y part of the
// commanded force is rendered, |f| = max_force_n giving level 0x7fff; the z part cannot be.
//
// Expiry: each uploaded effect plays for a finite time (kEffectHoldMs, then a fade to zero at
// the device's force-rate bound, the envelope's fade_length) and the driver refreshes it (re-
// uploads and restarts it) at least every kEffectRefreshMs. A master that stalls or dies
// stops refreshing it, and the device's force then ends by itself, gently.
#include <linux/input.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>

namespace teleop::master::evdev {

/// One axis's range as the kernel reports it (struct input_absinfo).
struct AxisRange {
  bool present = false;
  int minimum = 0;
  int maximum = 0;
};

/// Metres for the raw value of an axis whose range maps onto [lo, hi] [m].
inline double axis_to_m(int value, const AxisRange& a, double lo, double hi) {
  if (!a.present || a.maximum <= a.minimum) return 0.5 * (lo + hi);
  const double u =
      static_cast<double>(value - a.minimum) / static_cast<double>(a.maximum - a.minimum);
  return lo + std::clamp(u, 0.0, 1.0) * (hi - lo);
}

/// A constant-force effect's level and direction.
struct ConstantForce {
  std::int16_t level = 0;       ///< 0 .. 0x7fff
  std::uint16_t direction = 0;  ///< 0x0000 +y, 0x4000 -x, 0x8000 -y, 0xC000 +x
  bool operator==(const ConstantForce& o) const {
    return level == o.level && direction == o.direction;
  }
  bool operator!=(const ConstantForce& o) const { return !(*this == o); }
};

/// The effect for a force [N] (device frame); full scale `max_force_n`. Non-finite gives zero.
inline ConstantForce force_to_effect(const Eigen::Vector3d& force_n, double max_force_n) {
  ConstantForce e;
  if (!force_n.allFinite() || max_force_n <= 0.0) return e;
  const double fx = force_n.x(), fy = force_n.y();
  const double mag = std::hypot(fx, fy);
  if (mag <= 0.0) return e;
  e.level = static_cast<std::int16_t>(std::lround(std::min(mag / max_force_n, 1.0) * 0x7fff));
  double theta = std::atan2(-fx, fy);  // 0 at +y, pi/2 at -x
  if (theta < 0.0) theta += 2.0 * M_PI;
  e.direction = static_cast<std::uint16_t>(
      static_cast<long>(std::lround(theta / (2.0 * M_PI) * 65536.0)) & 0xffff);
  return e;
}

/// The planar force [N] an effect renders (inverse of force_to_effect, z = 0).
inline Eigen::Vector3d effect_to_force(const ConstantForce& e, double max_force_n) {
  const double mag = static_cast<double>(e.level) / 0x7fff * max_force_n;
  const double theta = static_cast<double>(e.direction) / 65536.0 * 2.0 * M_PI;
  return Eigen::Vector3d(-mag * std::sin(theta), mag * std::cos(theta), 0.0);
}

/// How long an effect plays at its level after its last refresh before it fades [ms].
constexpr int kEffectHoldMs = 30;
/// The driver refreshes the effect at least this often [ms] (well inside kEffectHoldMs).
constexpr int kEffectRefreshMs = 10;

/// The fade of an effect of level `e.level` (full scale `max_force_n` [N]) to zero at the rate
/// bound `max_rate_n_per_s` [N/s] [ms], at least 1 for a non-zero level, at most 10 s.
inline int effect_fade_ms(const ConstantForce& e, double max_force_n, double max_rate_n_per_s) {
  if (e.level <= 0) return 0;
  if (!(max_rate_n_per_s > 0.0) || !(max_force_n > 0.0)) return 1;
  const double force_n = static_cast<double>(e.level) / 0x7fff * max_force_n;
  const double ms = std::ceil(force_n / max_rate_n_per_s * 1e3);
  return static_cast<int>(std::clamp(ms, 1.0, 10000.0));
}

/// The Linux effect the driver uploads for `e` (id -1: a new one): a constant force that plays
/// kEffectHoldMs at its level, then fades to zero over effect_fade_ms and ends.
inline ff_effect make_effect(const ConstantForce& e, int id, double max_force_n,
                             double max_rate_n_per_s) {
  ff_effect effect{};
  effect.type = FF_CONSTANT;
  effect.id = static_cast<std::int16_t>(id);
  effect.direction = e.direction;
  effect.u.constant.level = e.level;
  const int fade_ms = effect_fade_ms(e, max_force_n, max_rate_n_per_s);
  effect.u.constant.envelope.attack_length = 0;
  effect.u.constant.envelope.attack_level = 0;
  effect.u.constant.envelope.fade_length = static_cast<std::uint16_t>(fade_ms);
  effect.u.constant.envelope.fade_level = 0;
  effect.replay.length = static_cast<std::uint16_t>(kEffectHoldMs + fade_ms);
  effect.replay.delay = 0;
  return effect;
}

}  // namespace teleop::master::evdev
