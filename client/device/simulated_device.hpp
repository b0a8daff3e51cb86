#pragma once
// SimulatedDevice: a virtual 6-DoF haptic device held by a modelled operator.
//
// Translation (3 DoF, full dynamics): the handle is the master M(s) of the paper's Fig. 10,
// a mass m_d with viscous damping b_d per axis, rigidly held by the hand (mass m_h), pushed
// by the hand impedance and the device force:
//     (m_d + m_h) a = K_h (x_d - x) + B_h (v_d - v) + F_device - b_d v
// integrated by semi-implicit Euler in advance(dt). Orientation (3 DoF) is kinematic: it
// follows the script's intended orientation; torques are accepted and recorded only.
// Deterministic; read/write/advance allocate nothing.
#include "client/device/haptic_device.hpp"
#include "client/device/operator_model.hpp"

namespace teleop::master {

/// Dynamics of the virtual device (per translational axis).
struct SimulatedDeviceParams {
  DeviceSpec spec;                       ///< limits; forces above max_force_n are clipped
  double device_mass_kg = 0.1;           ///< m_d: moving mass of the handle [kg]
  double device_damping_ns_per_m = 0.5;  ///< b_d: viscous damping per axis [N s/m]
  HandImpedance hand;                    ///< the operator's hand
  OperatorScript script;                 ///< what the operator intends to do
  bool clamp_to_workspace = true;        ///< hard stops at the workspace box
};

/// Virtual device with an operator model. See the file comment for the dynamics.
class SimulatedDevice final : public HapticDevice {
 public:
  explicit SimulatedDevice(SimulatedDeviceParams params);

  void configure() override;
  void activate() override;
  void deactivate() override;
  DeviceReading read() override;
  void write(const Eigen::Vector3d& force_n, const Eigen::Vector3d& torque_nm) override;
  void advance(double dt_s) override;
  const DeviceSpec& spec() const override { return params_.spec; }
  DeviceLifecycle state() const override { return state_; }

  /// Puts the handle at the script's start, at rest, time zero.
  void reset();
  /// Force the hand applied during the last advance() [N] (the operator's f_h).
  const Eigen::Vector3d& hand_force_n() const { return hand_force_n_; }
  /// Force actually applied by the actuators during the last advance() [N] (after clipping).
  const Eigen::Vector3d& applied_force_n() const { return applied_force_n_; }
  /// What the operator intended at the current time.
  IntendedPose intended() const { return intended_pose(params_.script, time_s_); }
  /// Read-only access to the parameters.
  const SimulatedDeviceParams& params() const { return params_; }
  /// Replaces the script (e.g. between sweep runs); call reset() afterwards.
  void set_script(const OperatorScript& script) { params_.script = script; }

 private:
  SimulatedDeviceParams params_;
  DeviceLifecycle state_ = DeviceLifecycle::kUnconfigured;
  double time_s_ = 0.0;
  Eigen::Vector3d x_m_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_mps_ = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_ = Eigen::Quaterniond::Identity();
  Eigen::Vector3d w_radps_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d force_cmd_n_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d torque_cmd_nm_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d hand_force_n_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d applied_force_n_ = Eigen::Vector3d::Zero();
};

}  // namespace teleop::master
