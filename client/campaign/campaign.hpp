#pragma once
// A campaign: a YAML file that names the sessions to run (docs/campaigns.md). Each of its
// sweeps is the Cartesian product of its axes; the campaign's runs are the sweeps' runs in
// file order, numbered from 0 (the run id). A run is a pure function of its parameters: the
// same parameters and seed give the same row on any machine, in any order, on any core.
//
//   Campaign c = load_campaign("deploy/campaigns/delay_map.yaml");   // throws ConfigError
//   for (const RunParams& p : c.runs) ...                            // run_one(c, p)
//
// Two models of the slave:
//   point: the press task of teleop_bench delay (client/analysis/press_scenario.hpp): the
//          server's world step on a tool world with one object (sphere or wall) under a
//          point tool; the linear model gives each run its analytic delay margin;
//   world: a scene file (robot, deformable bodies, planes) stepped by the same server cycle,
//          the master homing the slave first as teleop_master does against a live server.
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "common/config/config.hpp"

#include "client/device/replay_device.hpp"

namespace teleop::harness {
struct SceneModel;  // common/harness/in_process.hpp
}

namespace teleop::campaign {

/// Which slave the runs step (see the file comment).
enum class SlaveModel { kPoint, kWorld };

/// Every parameter of one run. Units in the names; 0 where a field says "0: default".
struct RunParams {
  std::size_t id = 0;  ///< position in the campaign's expansion
  std::string sweep;   ///< the sweep's name
  std::string scene;   ///< world: the scene file as the campaign names it; point: ""
  std::string environment = "sphere";  ///< point: sphere | wall; world: ""
  double stiffness_n_per_m = 2000.0;   ///< point: the object's k [N/m]
  double damping_ns_per_m = 0.0;       ///< point: the object's b [N s/m]; 0: sphere 5, wall 50
  std::string script = "press-slip";   ///< operator script
  /// A recorded operator trajectory (replay CSV, device frame, as the campaign names it) the
  /// device plays instead of the script; "": the script.
  std::string trajectory;
  double press_depth_m = 0.02;  ///< press-slip depth below the surface [m]
  double tremor_m = 1e-4;       ///< hand tremor amplitude [m]
  /// position-position | force-position | wave-variables | tdpa (on position-position) |
  /// tdpa-fp (tdpa on force-position) | model-mediated
  std::string scheme = "position-position";
  double gain = 0.0;         ///< position-like: K_pm = K_ps [N/m]; force-like: K_f [-]; 0: default
  double delay_ms = 0.0;     ///< one-way delay, each direction [ms]
  double jitter_ms = 0.0;    ///< jitter scale, each direction [ms]
  double loss = 0.0;         ///< Bernoulli loss probability, each direction [0, 1]
  double burst_p_gb = 0.0;   ///< Gilbert-Elliott good-to-bad probability per sample (0: off)
  double burst_p_bg = 1.0;   ///< Gilbert-Elliott bad-to-good probability per sample
  double max_force_n = 0.0;  ///< the device's peak force [N]; 0: the simulated device's 10 N
  std::uint64_t seed = 1;    ///< channel seeds (forward = seed, backward = seed + 1)
};

/// Column groups of the results table a campaign asks for (`measure:`).
struct Measures {
  bool stability = true, errors = true, transparency = true, energy = true, faults = true,
       channels = true;
};

/// A loaded campaign: its settings and every run, expanded and checked.
struct Campaign {
  std::string file;  ///< where it was loaded from
  std::string name;
  SlaveModel model = SlaveModel::kPoint;
  double duration_s = 0.0;  ///< session length [s]; 0: the script's length + 3 s (point),
                            ///< + 1 s (world), at least 2 s
  double homing_s = 1.5;    ///< world: homing before the session [s]
  Measures measures;
  std::vector<RunParams> runs;
  /// world: each scene named by a run, loaded once (key: the name as in RunParams::scene).
  std::map<std::string, std::shared_ptr<const harness::SceneModel>> scenes;
  /// Each recorded trajectory named by a run, loaded once (key as in RunParams::trajectory).
  std::map<std::string, std::shared_ptr<const std::vector<master::ReplaySample>>> trajectories;
};

/// Largest number of runs a campaign may expand to.
constexpr std::size_t kMaxRuns = 10'000'000;

/// Loads, expands and validates a campaign file: unknown keys, values out of range, axes that
/// do not apply to the model, scenes that do not load, and combinations the controller or the
/// delay channel refuse are all reported naming the file, the field, the value and the allowed
/// range. @throws config::ConfigError.
Campaign load_campaign(const std::string& file);
/// The same from YAML text (`file` used in messages and to resolve scene paths).
Campaign parse_campaign(const std::string& text, const std::string& file);

/// The controller scheme and tdpa base of a campaign scheme label ("tdpa-fp" is tdpa on
/// force-position), as the scheme's variants declare them (client/control/scheme_traits.hpp).
struct SchemeLaw {
  std::string scheme, tdpa_base;
  /// The gain axis is K_f (else K_pm = K_ps): the law is not position-based
  /// (SchemeTraits::position_based).
  bool force_gain = false;
};
/// @throws ConfigError naming the labels if `label` is none of scheme_labels().
SchemeLaw scheme_law(const std::string& label);
/// Every scheme label a campaign accepts (master::scheme_variant_labels()).
const std::vector<std::string>& scheme_labels();

/// A digest of everything that decides the campaign's rows (model, settings, every run's
/// parameters, the table's columns): 16 hex digits. Two folders hold the same campaign iff
/// their digests agree.
std::string campaign_digest(const Campaign& c);

}  // namespace teleop::campaign
