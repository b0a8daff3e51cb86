#include "client/device/simulated_device.hpp"

#include <algorithm>
#include <utility>

#include "common/config/config.hpp"

namespace teleop::master {

SimulatedDevice::SimulatedDevice(SimulatedDeviceParams params) : params_(std::move(params)) {}

void SimulatedDevice::configure() {
  const auto& p = params_;
  if (!(p.device_mass_kg + p.hand.mass_kg > 0.0)) {
    throw config::ConfigError("simulated device: device_mass_kg + hand.mass_kg must be > 0");
  }
  if (p.device_damping_ns_per_m < 0.0 || p.hand.damping_ns_per_m < 0.0 ||
      p.hand.stiffness_n_per_m < 0.0) {
    throw config::ConfigError("simulated device: damping and stiffness must be >= 0");
  }
  if (!(p.spec.max_force_n > 0.0)) {
    throw config::ConfigError("simulated device: spec.max_force_n must be > 0");
  }
  reset();
  state_ = DeviceLifecycle::kInactive;
}

void SimulatedDevice::activate() {
  if (state_ == DeviceLifecycle::kUnconfigured) configure();
  state_ = DeviceLifecycle::kActive;
}

void SimulatedDevice::deactivate() {
  force_cmd_n_.setZero();
  torque_cmd_nm_.setZero();
  if (state_ == DeviceLifecycle::kActive) state_ = DeviceLifecycle::kInactive;
}

void SimulatedDevice::reset() {
  time_s_ = 0.0;
  const IntendedPose want = intended_pose(params_.script, 0.0);
  x_m_ = want.position_m;
  v_mps_.setZero();
  q_ = want.orientation;
  w_radps_.setZero();
  force_cmd_n_.setZero();
  torque_cmd_nm_.setZero();
  hand_force_n_.setZero();
  applied_force_n_.setZero();
}

DeviceReading SimulatedDevice::read() {
  DeviceReading r;
  r.time_s = time_s_;
  r.position_m = x_m_;
  r.orientation = q_;
  r.linear_velocity_mps = v_mps_;
  r.angular_velocity_radps = w_radps_;
  r.buttons = state_ == DeviceLifecycle::kActive ? 1u : 0u;
  r.valid = state_ == DeviceLifecycle::kActive;
  return r;
}

void SimulatedDevice::write(const Eigen::Vector3d& force_n, const Eigen::Vector3d& torque_nm) {
  if (state_ != DeviceLifecycle::kActive) return;
  force_cmd_n_ = force_n;
  torque_cmd_nm_ = torque_nm;
}

void SimulatedDevice::advance(double dt) {
  const auto& p = params_;
  // the actuators clip at the spec's peak force (last line of defence)
  applied_force_n_ = state_ == DeviceLifecycle::kActive
                         ? saturate_norm(force_cmd_n_, p.spec.max_force_n)
                         : Eigen::Vector3d::Zero();
  // the hand tracks the intended trajectory through its impedance
  const IntendedPose want = intended_pose(p.script, time_s_);
  hand_force_n_ = hand_force(p.hand, want, x_m_, v_mps_);
  const double m = p.device_mass_kg + p.hand.mass_kg;
  const Eigen::Vector3d f = hand_force_n_ + applied_force_n_ - p.device_damping_ns_per_m * v_mps_;
  // semi-implicit Euler
  v_mps_ += dt * f / m;
  x_m_ += dt * v_mps_;
  if (p.clamp_to_workspace) {
    for (int i = 0; i < 3; ++i) {
      if (x_m_[i] < p.spec.workspace_min_m[i]) {
        x_m_[i] = p.spec.workspace_min_m[i];
        v_mps_[i] = std::max(0.0, v_mps_[i]);
      } else if (x_m_[i] > p.spec.workspace_max_m[i]) {
        x_m_[i] = p.spec.workspace_max_m[i];
        v_mps_[i] = std::min(0.0, v_mps_[i]);
      }
    }
  }
  // orientation is kinematic: it follows the intention
  time_s_ += dt;
  const IntendedPose next = intended_pose(p.script, time_s_);
  q_ = next.orientation;
  w_radps_ = next.angular_velocity_radps;
}

}  // namespace teleop::master
