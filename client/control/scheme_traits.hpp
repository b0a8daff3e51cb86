#pragma once
// What the code shared by every scheme asks of a scheme, answered by the scheme itself.
//
// Each scheme class in client/control/schemes/ declares, next to its parameters(), a static
// traits(const ControllerParams&) (the answers may depend on its parameters, e.g. on a base law
// the scheme runs on) and may declare variants() (labels that fix some of its parameters, as
// the campaigns name them; docs/control.md lists them). The registry
// (client/control/schemes/registry.cpp) reads them; live tuning (tuning.cpp), the press
// scenario's theory (client/analysis/press_scenario.cpp), the link's verdict
// (client/metrics/link_verdict.cpp), the campaigns (client/campaign/campaign.cpp) and
// teleop_master's default rates ask through scheme_traits() and never compare scheme names.
// Configuration time only, never in the control loop.
#include <cstdint>
#include <string>
#include <vector>

#include "client/control/controller_params.hpp"

namespace teleop::master {

/// A scheme's answers to the shared code (see the file comment).
struct SchemeTraits {
  /// The gains a live tuning request may change: TuningField bits (client/control/tuning.hpp)
  /// of K_pm, B_m, K_f and K_ps. The injected delays are tunable for every scheme and are not
  /// listed here.
  std::uint32_t tunable_gains = 0;
  /// The law couples the master to the slave's position, so a scheme's one gain is the
  /// stiffness K_pm = K_ps [N/m]; otherwise the gain is the force gain K_f [-] (the press
  /// scenario's and the campaigns' gain axis).
  bool position_based = false;
  /// Passive at any delay by design (its theory is stability at every delay); such a scheme
  /// tolerates a longer network round trip before the link is judged degraded.
  bool passive_by_design = false;
  /// The linearised press loop (client/analysis: position-position or force-position, chosen
  /// by position_based) describes the law without its passivity layer, so a delay margin is
  /// computed from it. False: the scheme's theory is stability at every delay, an infinite
  /// margin.
  bool linear_loop_model = true;
  /// The master's loop rate [Hz] unless told otherwise (0: the master's own default).
  double default_rate_hz = 0.0;
  /// The master's command rate [Hz] unless told otherwise, at most the loop rate (0: the
  /// master's own default).
  double default_command_rate_hz = 0.0;
};

/// A label that names a scheme with some of its parameters fixed (a base law, say). A scheme
/// without variants is named by its own name only.
struct SchemeVariant {
  const char* label;
  /// Sets the parameters the label fixes (p.scheme is set already).
  void (*apply)(ControllerParams& p);
};

/// The traits of the scheme `p.scheme` with the parameters `p`.
/// @throws ConfigError naming the allowed names if the scheme is unknown.
SchemeTraits scheme_traits(const ControllerParams& p);
/// The traits of `scheme` at its default parameters. @throws ConfigError as above.
SchemeTraits scheme_traits(const std::string& scheme);

/// Every scheme label, in the registry's order: a scheme's variants in place of its name, or
/// its name if it has none.
const std::vector<std::string>& scheme_variant_labels();
/// Sets p.scheme and the parameters `label` fixes (the other fields are left as they are).
/// @throws ConfigError naming the labels if `label` is none of scheme_variant_labels().
void apply_scheme_variant(const std::string& label, ControllerParams& p);

}  // namespace teleop::master
