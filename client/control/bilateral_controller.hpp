#pragma once
// Bilateral control schemes of the master side, chosen by name.
//
// position-position (paper Fig. 10): the master feels a spring to the (delayed) slave
//   position and a damper:      F_m = K_pm (x_s' - x_m) - B_m v_m,   x_s' = slave pos. in
//   master frame; the slave is commanded x_c = map(x_m) and tracks it with its own K_ps.
// force-position (paper Fig. 11): the master sends x_m; the slave returns its contact force
//   f_e (environment on tip); the master renders   F_m = K_f beta R^T f_e - B_m v_m.
//   (The paper writes F_m = -K_f f_e with f_e the force the slave exerts on the environment;
//   ours is the reaction, hence the sign.)
//
// Lifecycle: configure(params, spec) validates and clamps gains against the DeviceSpec
// (CHAI3D style: K <= max stiffness, B <= max damping); activate(reading) latches the start;
// update() is real-time safe (no allocation) and returns the device force (saturated to the
// spec's peak force) and the command for the slave.
//
// Extension (wave variables, time-domain passivity): a scheme overrides compute(); the base
// pre-fills the command with the mapped pose, so a wave scheme writes command.wave_u and
// reads slave.wave_v, and a passivity controller post-processes out.force_n with its energy
// observer before the base saturates it. SlaveCommand/SlaveSample already carry wave_u/v.
#include <memory>
#include <string>
#include <vector>

#include "client/control/bilateral_types.hpp"
#include "client/device/haptic_device.hpp"
#include "common/config/config.hpp"

namespace teleop::master {

/// Parameters of a bilateral controller. Defaults with units; 0 means "derive" where noted.
struct ControllerParams {
  std::string scheme = "position-position";  ///< "position-position" | "force-position"
  WorkspaceMap workspace;                    ///< master -> slave map and force scaling
  double slave_stiffness_n_per_m = 400.0;    ///< K_ps requested from the slave [N/m]
  /// K_pm [N/m]; 0 = transparent choice alpha * beta * K_ps (felt force = beta * contact force
  /// in steady contact). Clamped to the spec's max stiffness.
  double master_stiffness_n_per_m = 0.0;
  double master_damping_ns_per_m = 2.0;  ///< B_m [N s/m]; clamped to the spec's max damping
  double force_gain = 1.0;               ///< K_f of force-position [-] (soft/hard contact feel)
  double max_force_n = 0.0;              ///< output saturation [N]; 0 = spec.max_force_n
  bool send_velocity = true;             ///< command the mapped master velocity too

  /// Throws ConfigError naming the field if a value is out of range.
  void validate() const;
};

/// Reads controller parameters from a YAML mapping (keys as the field names; workspace as
/// {offset_m: [x,y,z], position_scale, force_scale}). @throws ConfigError.
ControllerParams controller_params_from_yaml(const config::Node& node);

/// One controller cycle's result.
struct ControlOutput {
  Eigen::Vector3d force_n = Eigen::Vector3d::Zero();    ///< device force, master frame [N]
  Eigen::Vector3d torque_nm = Eigen::Vector3d::Zero();  ///< device torque [N m]
  SlaveCommand command;                                 ///< to send to the slave
  double unsaturated_force_n = 0.0;                     ///< |F| before saturation [N]
  bool saturated = false;                               ///< |F| was clipped to the limit
  bool have_slave = false;                              ///< a slave sample was available
};

/// Base of the bilateral schemes. See the file comment.
class BilateralController {
 public:
  virtual ~BilateralController() = default;

  /// Validates `params` and clamps gains against `spec`. @throws ConfigError.
  void configure(const ControllerParams& params, const DeviceSpec& spec);
  /// Starts a session at the current master reading; resets the sequence counter.
  void activate(const DeviceReading& master);
  /// Stops: later updates return zero force and a disabled (hold) command.
  void deactivate();
  /// One cycle: master reading, newest (delayed) slave sample (valid=false if none yet),
  /// period dt [s]. Real-time safe.
  ControlOutput update(const DeviceReading& master, const SlaveSample& slave, double dt_s);

  /// Scheme name ("position-position", ...).
  virtual const char* name() const = 0;
  /// Scheme id (SCHEME_* constant).
  virtual SchemeId scheme() const = 0;

  /// Parameters after clamping (what is actually used).
  const ControllerParams& params() const { return params_; }
  /// Effective K_pm [N/m] after derivation and clamping.
  double master_stiffness_n_per_m() const { return k_pm_; }
  /// Effective B_m [N s/m] after clamping.
  double master_damping_ns_per_m() const { return b_m_; }
  /// Effective force limit [N].
  double force_limit_n() const { return f_max_; }
  /// True between activate() and deactivate().
  bool active() const { return active_; }

 protected:
  /// Scheme-specific part: fill out.force_n (master frame, unsaturated) and adjust
  /// out.command if needed. out.command is pre-filled with the mapped master pose.
  virtual void compute(const DeviceReading& master, const SlaveSample& slave, double dt_s,
                       ControlOutput& out) = 0;

  ControllerParams params_;
  DeviceSpec spec_;
  double k_pm_ = 0.0;
  double b_m_ = 0.0;
  double f_max_ = 0.0;

 private:
  bool active_ = false;
  std::uint64_t seq_ = 0;
};

/// Fig. 10: position-position.
class PositionPositionController final : public BilateralController {
 public:
  const char* name() const override { return "position-position"; }
  SchemeId scheme() const override { return SchemeId::kPositionPosition; }

 protected:
  void compute(const DeviceReading& master, const SlaveSample& slave, double dt_s,
               ControlOutput& out) override;
};

/// Fig. 11: force-position.
class ForcePositionController final : public BilateralController {
 public:
  const char* name() const override { return "force-position"; }
  SchemeId scheme() const override { return SchemeId::kForcePosition; }

 protected:
  void compute(const DeviceReading& master, const SlaveSample& slave, double dt_s,
               ControlOutput& out) override;
};

/// Creates a controller by scheme name. @throws ConfigError naming the allowed names.
std::unique_ptr<BilateralController> make_controller(const std::string& scheme);
/// The scheme names make_controller() accepts.
std::vector<std::string> controller_names();

}  // namespace teleop::master
