#pragma once
// Bilateral control schemes of the master side, chosen by name: the base class here, its
// parameters in client/control/controller_params.hpp; each scheme's law (and its own
// parameters) in client/control/schemes/ (one file each), the table of names in
// client/control/schemes/registry.cpp.
//
// Lifecycle: configure(params, spec) validates and clamps gains against the DeviceSpec
// (CHAI3D style: K <= max stiffness, B <= max damping); activate(reading) latches the start;
// update() is real-time safe (no allocation) and returns the device force (saturated to the
// spec's peak force) and the command for the slave.
//
// Extension: a scheme overrides compute() (and on_configure(), on_activate(), finish() if it
// keeps state); the base pre-fills the command with the mapped pose and saturates the force
// between compute() and finish(). It declares its static traits() (client/control/
// scheme_traits.hpp: what the shared code asks of it), and its parameters() and variants() if
// it has any.
#include <memory>
#include <string>
#include <vector>

#include "client/control/controller_params.hpp"
#include "client/control/scheme_traits.hpp"
#include "client/device/haptic_device.hpp"
#include "common/config/config.hpp"
#include "common/control/bilateral_types.hpp"

namespace teleop::master {

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
  /// The scheme's own parameters (none here; a scheme with some declares its own parameters()
  /// in its file, and the registry reads it).
  static const std::vector<ControllerParam>& parameters();
  /// The scheme's variants (none here: the scheme is named by its name only; a scheme with
  /// some declares its own variants(), and the registry reads it). Every scheme also declares
  /// `static SchemeTraits traits(const ControllerParams&)`, which the base does not: the
  /// registry refuses to compile a scheme without it.
  static const std::vector<SchemeVariant>& variants();
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
  /// Impedance b of the scheme's wave channel after derivation and clamping [N s/m]; 0 for the
  /// schemes without one.
  virtual double wave_impedance_ns_per_m() const { return 0.0; }

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

/// Creates a controller by scheme name (client/control/schemes/registry.cpp).
/// @throws ConfigError naming the allowed names.
std::unique_ptr<BilateralController> make_controller(const std::string& scheme);
/// The scheme names make_controller() accepts, in the registry's order.
const std::vector<std::string>& controller_names();

}  // namespace teleop::master
