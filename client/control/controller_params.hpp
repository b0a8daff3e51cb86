#pragma once
// The parameters of the bilateral controllers and the one table that declares them.
//
// Each parameter is declared once, as a ControllerParam (YAML key, teleop_master flag, unit,
// help, range or allowed values, and the field of ControllerParams it reads and writes); its
// default is the member initialiser of ControllerParams. The parameters every scheme uses are
// declared in controller_params.cpp; a scheme's own parameters in its scheme file
// (client/control/schemes/NAME.cpp, as the static parameters() of its class); the scheme
// registry (client/control/schemes/registry.cpp) joins them into controller_param_table().
// The YAML loader, validate(), teleop_master's flags (client/control/controller_flags.hpp) and
// the table of docs/configuration.md (`teleop_master --print-parameters`) all read that table.
// Everything here runs at configuration only, never in the control loop.
#include <string>
#include <variant>
#include <vector>

#include "common/config/config.hpp"
#include "common/control/bilateral_types.hpp"

namespace teleop::master {

/// Parameters of a bilateral controller. Defaults with units; 0 means "derive" where noted.
/// Ranges, units and help: controller_param_table() (docs/configuration.md shows it).
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

  /// Checks every parameter of controller_param_table() against its range or allowed values.
  /// @throws ConfigError "controller: FIELD = VALUE is out of the allowed range [lo, hi]" (a
  /// choice: "controller: FIELD 'VALUE' is unknown (allowed: a, b)").
  void validate() const;
};

/// What a parameter holds, from the type of its field.
enum class ParamKind {
  kNumber,  ///< a double within [lo, hi]
  kBool,    ///< true or false
  kChoice,  ///< one of `choices`
  kPoint,   ///< three doubles, each within [lo, hi]
};

/// One parameter of ControllerParams, declared once (see the file comment).
struct ControllerParam {
  /// The field of ControllerParams (or of its WorkspaceMap) the parameter reads and writes.
  using Field = std::variant<double ControllerParams::*, bool ControllerParams::*,
                             std::string ControllerParams::*, double WorkspaceMap::*,
                             Eigen::Vector3d WorkspaceMap::*>;

  /// Key in a `controller:` mapping; "workspace.NAME" for a key of its `workspace:` mapping.
  std::string key{};
  /// teleop_master's flag ("--kps"), or "" for none.
  std::string flag{};
  /// Unit ("N/m", "-" for a ratio), or "" for a choice or a boolean.
  std::string unit{};
  /// What it is, with its symbol and what 0 means where 0 derives a value.
  std::string help{};
  Field field{};
  double lo = 0.0;  ///< number, point: smallest allowed value (each component)
  double hi = 0.0;  ///< number, point: largest allowed value (each component)
  /// choice: the allowed values.
  std::vector<std::string> choices{};
  /// bool with a flag: the flag is a switch that sets the field to this value, and this is
  /// what the switch does (its --help).
  bool switch_sets = true;
  std::string switch_help{};
  /// The scheme the parameter belongs to ("" for all; set by the scheme registry).
  std::string scheme{};

  ParamKind kind() const;
  /// The number (kNumber) the field holds in `p`.
  double number(const ControllerParams& p) const;
  /// Sets the number (kNumber) of the field in `p`, unchecked.
  void set_number(ControllerParams& p, double v) const;
  /// The field as text, as YAML and the docs write it ("400", "true", "[0, 0, 0]").
  std::string text(const ControllerParams& p) const;
  /// The allowed range or values as the docs write them ("[0, 1e6]", "a, b").
  std::string allowed_text() const;
  /// The flag's --help: the scheme, the help (a switch: switch_help), the unit and the range.
  std::string flag_help() const;
  /// Checks the field of `p`. @throws ConfigError (see ControllerParams::validate()).
  void check(const ControllerParams& p) const;
  /// Sets the field of `p` from `node` if `node` holds the key (file, field, value and range
  /// in the message otherwise). `node` is the `controller:` mapping. @throws ConfigError.
  void read(const config::Node& node, ControllerParams& p) const;
  /// Sets the field of `p` from a flag's text (a switch: `text` is not used).
  /// @throws ConfigError naming the flag, the text and the range.
  void apply_flag(const std::string& text, ControllerParams& p) const;
};

/// The parameters every scheme uses, in the order of the docs' table.
const std::vector<ControllerParam>& common_controller_params();
/// Every parameter: the common ones, then each scheme's own (client/control/schemes/) in the
/// registry's order, each with its `scheme` set.
const std::vector<ControllerParam>& controller_param_table();
/// The parameters of one scheme (its own only; the common ones apply to all).
/// @throws ConfigError naming the allowed names if `scheme` is unknown.
std::vector<ControllerParam> scheme_params(const std::string& scheme);

/// Reads controller parameters from a YAML mapping (keys of controller_param_table(); unknown
/// keys are refused with the list of known ones). @throws ConfigError.
ControllerParams controller_params_from_yaml(const config::Node& node);

/// The table as markdown (key, flag, unit, default, range, help), one row a parameter, ending
/// with a newline: what `teleop_master --print-parameters` prints and docs/configuration.md
/// holds between `<!-- controller-parameters -->` and `<!-- /controller-parameters -->`.
std::string controller_params_markdown();

/// A number as the table writes it (common/config/config.hpp).
using config::param_number_text;

}  // namespace teleop::master
