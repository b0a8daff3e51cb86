#pragma once
// Bilateral control schemes of the master side, chosen by name.
//
// position-position (paper Fig. 10): the master feels a spring to the (delayed) slave
//   position and a damper:      F_m = K_pm (x_s' - x_m) - B_m v_m,   x_s' = slave pos. in
//   master frame; the slave is commanded x_c = map(x_m) and tracks it with its own K_ps.
// force-position (paper Fig. 11): the master sends x_m; the slave returns its contact force
//   f_e (environment on tip); the master renders   F_m = K_f beta R^T f_e - s B_m v_m, the
//   damping share s ramped (contact_damping_ramp_s) to 1 while the slave is in contact and to
//   0 in free space: nothing there for the damper to stabilise, so free motion is not dragged.
//   (The paper writes F_m = -K_f f_e with f_e the force the slave exerts on the environment;
//   ours is the reaction, hence the sign.)
//
// Lifecycle: configure(params, spec) validates and clamps gains against the DeviceSpec
// (CHAI3D style: K <= max stiffness, B <= max damping); activate(reading) latches the start;
// update() is real-time safe (no allocation) and returns the device force (saturated to the
// spec's peak force) and the command for the slave.
//
// wave-variables (Niemeyer & Slotine; Anderson & Spong 1989): the master port of a wave
//   channel of impedance b (common/control/wave_variables.hpp). The device renders
//   -beta R^T F_m - B_m v_m with F_m = b xdot_m - sqrt(2b) v_m in the slave frame; the
//   command carries the forward wave u, its integral and its energy; the slave decodes them
//   with its contact force (common/control/slave_port.hpp) and returns the backward wave.
// tdpa (Hannaford & Ryu 2002; Ryu, Artigas & Preusche 2010): position-position or
//   force-position (tdpa_base) with the master's passivity observer and controller
//   (common/control/time_domain_passivity.hpp): the force is modified by the adaptive damping
//   that keeps the master port's output energy within the slave port's input energy
//   received; the command carries the master port's input energy for the slave's PC.
//
// model-mediated (docs/control.md): the slave sends, with each state, a local model of what its
//   tip touches (common/control/contact_model.hpp: a half-space with a stiffness and damping
//   estimated online); the master renders F_m = beta R^T F_model(x_m, v_m) - B_m v_m from its
//   own position at its own rate, and commands the slave x_c = map(x_m) as position-position
//   does. Model updates are blended in (time constant mmt_blend_s); a blend step that would
//   raise the model's stored energy at the master's position by more than an energy budget
//   (refilled at mmt_energy_rate_w up to mmt_energy_burst_j) moves the surface out instead, so
//   late or changing models cannot push the operator with more than that energy.
//
// Extension: a scheme overrides compute() (and on_configure(), on_activate(), finish() if it
// keeps state); the base pre-fills the command with the mapped pose and saturates the force
// between compute() and finish().
#include <memory>
#include <string>
#include <vector>

#include "client/device/haptic_device.hpp"
#include "common/config/config.hpp"
#include "common/control/bilateral_types.hpp"
#include "common/control/time_domain_passivity.hpp"
#include "common/control/wave_variables.hpp"

namespace teleop::master {

/// Parameters of a bilateral controller. Defaults with units; 0 means "derive" where noted.
struct ControllerParams {
  /// "force-position" (the default: the design card's loop) | "position-position" |
  /// "wave-variables" | "tdpa" | "model-mediated"
  std::string scheme = "force-position";
  WorkspaceMap workspace;                  ///< master -> slave map and force scaling
  double slave_stiffness_n_per_m = 400.0;  ///< K_ps requested from the slave [N/m]
  /// K_pm [N/m]; 0 = transparent choice alpha * beta * K_ps (felt force = beta * contact force
  /// in steady contact). Clamped to the spec's max stiffness.
  double master_stiffness_n_per_m = 0.0;
  double master_damping_ns_per_m = 2.0;  ///< B_m [N s/m]; clamped to the spec's max damping
  double force_gain = 1.0;               ///< K_f of force-position [-] (soft/hard contact feel)
  double max_force_n = 0.0;              ///< output saturation [N]; 0 = spec.max_force_n
  bool send_velocity = true;             ///< command the mapped master velocity too
  /// Wave impedance b [N s/m] of wave-variables; 0 = derive K_ps * wave_time_constant_s.
  /// Clamped so that the damping the device renders, alpha beta b, stays within the spec's
  /// max damping.
  double wave_impedance_ns_per_m = 0.0;
  double wave_time_constant_s = 0.025;  ///< tau_b of the derived b = K_ps tau_b [s]
  bool wave_matched = true;  ///< the slave terminates the channel with a damper b (no echo)
  /// Cutoff of the first-order low-pass on the backward wave at the master [Hz] (0: off).
  /// Passive (it never puts out more wave energy than it receives); it removes the echo a
  /// stiff contact sends back and forth between the device and the slave.
  double wave_filter_hz = 10.0;
  /// Base law of tdpa: "position-position" | "force-position".
  std::string tdpa_base = "position-position";
  /// model-mediated: time constant of the blend toward each new model [s].
  double mmt_blend_s = 0.02;
  /// force-position and model-mediated: time to ramp B_m in at contact and out after it [s].
  double contact_damping_ramp_s = 0.02;
  /// model-mediated: energy model updates may add at the master per second [W], and at once [J].
  double mmt_energy_rate_w = 0.05;
  double mmt_energy_burst_j = 2e-4;

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

  /// Live gains (client/control/tuning.hpp): K_pm and B_m clamped to the spec as configure()
  /// does, K_f and K_ps as given (checked by check_tuning()). Real-time safe.
  void retune(double master_stiffness_n_per_m, double master_damping_ns_per_m, double force_gain,
              double slave_stiffness_n_per_m);

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
  /// The next activate() uses this session id (0: the next of a process-wide counter). The
  /// slave restarts its passivity state when the id changes; the master uses the slave's
  /// passivity fields only when they carry its own id.
  void set_session_id(std::uint32_t id) { next_session_ = id; }
  /// Session id of the running session.
  std::uint32_t session_id() const { return session_; }
  /// K_f of the environment force the scheme renders (1 unless force reflection is scaled).
  virtual double environment_force_gain() const { return 1.0; }

  /// Passivity bookkeeping of the master side (zero for the schemes without).
  struct PassivityStatus {
    double observer_j = 0.0;      ///< master-side observer: energy budget left [J] (>= 0)
    double dissipated_j = 0.0;    ///< energy removed by the master-side PC [J]
    double alpha_ns_per_m = 0.0;  ///< damping the PC added this cycle [N s/m]
  };
  virtual PassivityStatus passivity_status() const { return {}; }

 protected:
  /// Called at the end of configure() (params_, spec_, gains set). @throws ConfigError.
  virtual void on_configure() {}
  /// Called at the end of activate().
  virtual void on_activate(const DeviceReading& /*master*/) {}
  /// Called after saturation with the final force in `out` (record energies here).
  virtual void finish(const DeviceReading& /*master*/, const SlaveSample& /*slave*/,
                      double /*dt_s*/, ControlOutput& /*out*/) {}

  /// Scheme-specific part: fill out.force_n (master frame, unsaturated) and adjust
  /// out.command if needed. out.command is pre-filled with the mapped master pose.
  virtual void compute(const DeviceReading& master, const SlaveSample& slave, double dt_s,
                       ControlOutput& out) = 0;

  ControllerParams params_;
  DeviceSpec spec_;
  double k_pm_ = 0.0;
  double b_m_ = 0.0;
  double f_max_ = 0.0;
  std::uint32_t session_ = 0;

 private:
  bool active_ = false;
  std::uint64_t seq_ = 0;
  std::uint32_t next_session_ = 0;
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
  double environment_force_gain() const override { return params_.force_gain; }

 protected:
  void on_activate(const DeviceReading& master) override;
  void compute(const DeviceReading& master, const SlaveSample& slave, double dt_s,
               ControlOutput& out) override;

 private:
  double damping_share_ = 0.0;  // B_m's share now: 1 in contact, 0 in free space, ramped
};

/// Model-mediated teleoperation, master side (see the file comment).
class ModelMediatedController final : public BilateralController {
 public:
  const char* name() const override { return "model-mediated"; }
  SchemeId scheme() const override { return SchemeId::kModelMediated; }
  /// The model rendered now (slave frame), and the energy bookkeeping of model updates.
  struct ModelStatus {
    mmt::LocalModel rendered;
    double injected_j = 0.0;            ///< energy model updates added at the master [J]
    double budget_j = 0.0;              ///< what they may add now [J]
    std::uint64_t limited_updates = 0;  ///< blend steps held to the budget
    std::uint64_t models_received = 0;  ///< cycles with a valid model from the slave
    double damping_share = 0.0;         ///< of B_m, ramped to 1 while the model pushes
  };
  const ModelStatus& model_status() const { return status_; }

 protected:
  void on_activate(const DeviceReading& master) override;
  void compute(const DeviceReading& master, const SlaveSample& slave, double dt_s,
               ControlOutput& out) override;

 private:
  /// The rendered model one blend step toward `target` at master position x, within the budget.
  void blend_toward(const mmt::LocalModel& target, const Eigen::Vector3d& x, double dt_s);

  ModelStatus status_;
};

/// Wave variables, master side (see the file comment).
class WaveVariablesController final : public BilateralController {
 public:
  const char* name() const override { return "wave-variables"; }
  SchemeId scheme() const override { return SchemeId::kWaveVariables; }
  /// Effective wave impedance b after derivation and clamping [N s/m].
  double wave_impedance_ns_per_m() const { return b_; }
  /// The master port (waves, integrals, energies).
  const passivity::WaveMasterPort& port() const { return port_; }
  PassivityStatus passivity_status() const override;

 protected:
  void on_configure() override;
  void on_activate(const DeviceReading& master) override;
  void compute(const DeviceReading& master, const SlaveSample& slave, double dt_s,
               ControlOutput& out) override;

 private:
  double b_ = 0.0;
  passivity::WaveMasterPort port_;
  Eigen::Vector3d v_energy_rx_ = Eigen::Vector3d::Zero();
};

/// Time-domain passivity on top of position-position or force-position (see the file comment).
class TimeDomainPassivityController final : public BilateralController {
 public:
  const char* name() const override { return "tdpa"; }
  SchemeId scheme() const override { return SchemeId::kTimeDomainPassivity; }
  double environment_force_gain() const override {
    return force_position_ ? params_.force_gain : 1.0;
  }
  PassivityStatus passivity_status() const override;
  /// The master's observer/controller (master-frame energies).
  const passivity::ImpedancePassivityController& pc() const { return pc_; }
  /// Slave port energies received, converted to the master frame [J].
  double remote_in_j() const { return remote_in_j_; }
  double remote_out_j() const { return remote_out_j_; }

 protected:
  void on_configure() override;
  void on_activate(const DeviceReading& master) override;
  void compute(const DeviceReading& master, const SlaveSample& slave, double dt_s,
               ControlOutput& out) override;
  void finish(const DeviceReading& master, const SlaveSample& slave, double dt_s,
              ControlOutput& out) override;

 private:
  bool force_position_ = false;
  passivity::ImpedancePassivityController pc_;
  Eigen::Vector3d wanted_n_ = Eigen::Vector3d::Zero();
  double remote_in_j_ = 0.0;
  double remote_out_j_ = 0.0;
};

/// Creates a controller by scheme name. @throws ConfigError naming the allowed names.
std::unique_ptr<BilateralController> make_controller(const std::string& scheme);
/// The scheme names make_controller() accepts.
std::vector<std::string> controller_names();

}  // namespace teleop::master
