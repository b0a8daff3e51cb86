#include "client/device/external_device.hpp"

#include <utility>

#include "common/config/config.hpp"

namespace teleop::master {

ExternalDevice::ExternalDevice(DeviceSpec spec, double staleness_timeout_s)
    : spec_(std::move(spec)), timeout_s_(staleness_timeout_s) {}

void ExternalDevice::configure() {
  if (!(timeout_s_ > 0.0)) {
    throw config::ConfigError("external device: staleness timeout " + std::to_string(timeout_s_) +
                              " s must be > 0");
  }
  state_ = DeviceLifecycle::kInactive;
}

void ExternalDevice::activate() {
  if (state_ == DeviceLifecycle::kUnconfigured) configure();
  state_ = DeviceLifecycle::kActive;
}

void ExternalDevice::deactivate() {
  force_n_.setZero();
  torque_nm_.setZero();
  if (state_ == DeviceLifecycle::kActive) state_ = DeviceLifecycle::kInactive;
}

bool ExternalDevice::on_sample(const ExternalDeviceSample& s) {
  // newest wins; an older seq is accepted only once the link is stale (a driver restart)
  if (have_sample_ && s.seq <= newest_.seq && fresh()) return false;
  newest_ = s;
  have_sample_ = true;
  age_s_ = 0.0;
  return true;
}

void ExternalDevice::advance(double dt_s) {
  clock_s_ += dt_s;
  if (have_sample_) age_s_ += dt_s;
  const bool f = fresh();
  if (was_fresh_ && !f) ++stale_events_;
  was_fresh_ = f;
}

DeviceReading ExternalDevice::read() {
  DeviceReading r;
  r.time_s = clock_s_;
  if (!have_sample_) return r;
  r.position_m = newest_.position_m;
  r.orientation = newest_.orientation;
  r.linear_velocity_mps = newest_.linear_velocity_mps;
  r.angular_velocity_radps = newest_.angular_velocity_radps;
  r.buttons = newest_.buttons;
  r.valid = state_ == DeviceLifecycle::kActive && newest_.engaged && fresh();
  return r;
}

void ExternalDevice::write(const Eigen::Vector3d& force_n, const Eigen::Vector3d& torque_nm) {
  force_n_ = saturate_norm(force_n, spec_.max_force_n);
  torque_nm_ = saturate_norm(torque_nm, spec_.max_torque_nm);
}

ExternalDeviceCommand ExternalDevice::next_command() {
  ExternalDeviceCommand c;
  c.seq = ++command_seq_;
  c.state_seq = have_sample_ ? newest_.seq : 0;
  c.enable = state_ == DeviceLifecycle::kActive && have_sample_ && newest_.engaged && fresh();
  if (c.enable) {
    c.force_n = force_n_;
    c.torque_nm = torque_nm_;
  }
  return c;
}

}  // namespace teleop::master
