#pragma once
// The paper's Fig. 13 task as an in-process scenario: an operator (SimulatedDevice) approaches
// the top of an object, presses into it, slips sideways and departs, teleoperating a slave
// tool through delayed channels. The object is either the elastic sphere (a soft linear
// spring, k ~ 500-2e4 N/m, radius 0.25 m on the floor) or a stiff wall (a plane at the same
// height, k = 2e4 N/m). Used by the tests and by `teleop_bench delay`.
#include <string>

#include "client/analysis/stability_analysis.hpp"
#include "client/device/simulated_device.hpp"
#include "client/sim/loopback_session.hpp"
#include "common/sim/tool.hpp"

namespace teleop::master {

/// Which object the slave presses.
enum class Environment { kSphere, kWall };

/// Knobs of the scenario.
struct PressScenario {
  std::string scheme = "position-position";     ///< controller scheme
  std::string tdpa_base = "position-position";  ///< base law of "tdpa"
  Environment environment = Environment::kSphere;
  double env_stiffness_n_per_m = 2000.0;  ///< k of the object [N/m]
  double env_damping_ns_per_m = 5.0;      ///< b of the object [N s/m]
  /// PP and tdpa on PP: K_pm = K_ps [N/m] (0: 400); FP and tdpa on FP: K_f (0: 1) with
  /// K_ps = 400 N/m; wave-variables: K_ps [N/m] (0: 400), b derived from it (or as below).
  double gain = 0.0;
  double wave_impedance_ns_per_m = 0.0;  ///< b of wave-variables [N s/m] (0: derived)
  bool wave_matched = true;              ///< matched slave termination
  double one_way_delay_s = 0.0;          ///< delay each way [s]
  double jitter_s = 0.0;                 ///< jitter each way [s]
  double press_depth_m = 0.02;           ///< intended depth below the surface [m]
  double duration_s = 0.0;  ///< 0: one pass of the script plus 3 s (free motion after departing)
  std::uint64_t seed = 1;   ///< channel seeds (forward = seed, backward = seed + 1)
  bool safety = true;       ///< safety layer on
  HandImpedance hand;       ///< operator hand
  double tremor_m = 1e-4;   ///< hand tremor amplitude per component [m] (see OperatorScript)
};

/// A built scenario: device, slave and loop configuration, ready to run.
struct PressSetup {
  SimulatedDeviceParams device;
  /// The slave's tool law and its obstacles (floor and object): the world the slave steps is
  /// sim::tool_world_model(slave, ...) (server/node/world_slave.hpp runs it in-process).
  sim::ToolModel slave;
  LoopbackConfig loop;
};

/// Builds the setup for `s`. The sphere (radius 0.25 m) stands on the floor at the origin;
/// the master origin maps to the tool centre touching its top (0, 0, 0.55) m.
PressSetup build_press_setup(const PressScenario& s);

/// True if the scenario's law is position-based (SchemeTraits::position_based): its gain is
/// K_pm = K_ps and its linear model position-position.
/// @throws ConfigError naming the allowed schemes if s.scheme is unknown.
bool press_position_like(const PressScenario& s);

/// The linear model of the same setup in steady contact (for the analytic boundary). For tdpa
/// it is the base law without the passivity controller; wave-variables and model-mediated have
/// no such model (SchemeTraits::linear_loop_model).
LoopModel press_loop_model(const PressScenario& s, const PressSetup& setup);

/// Result of one run.
struct PressResult {
  Verdict verdict = Verdict::kStable;
  std::string reason;
  double position_error_rms_m = 0.0;
  double force_error_rms_n = 0.0;
  double max_device_force_n = 0.0;
  double max_controller_force_n = 0.0;  ///< before the safety layer [N]
  double energy_min_j = 0.0;
  double contact_time_s = 0.0;
  bool safety_cut = false;
  double analytic_margin_s = 0.0;       ///< one-way delay margin of the linear model [s]
                                        ///< (tdpa: of the base law; wave, mmt: infinite)
  bool analytic_stable = true;          ///< the linear model is stable at this delay (exact count)
  bool passive_scheme = false;          ///< passive for any delay by design (wave, tdpa, mmt)
  double passivity_dissipated_j = 0.0;  ///< master + slave passivity controllers [J]
  double min_observer_j = 0.0;          ///< lowest master-side observer value seen [J]
  // transparency (SessionMetrics, docs/control.md "Transparency"); NaN where not measured
  double free_force_mean_n = 0.0, free_force_p99_n = 0.0;
  double felt_force_ratio = 0.0, felt_stiffness_n_per_m = 0.0, environment_stiffness_n_per_m = 0.0,
         stiffness_ratio = 0.0;
};

/// Fills the result's metrics figures (verdict, errors, forces, transparency) from a session.
void fill_metrics(const SessionMetrics& m, PressResult& r);

/// Sets analytic_margin_s, analytic_stable and passive_scheme of `r` for `s`, as the scheme's
/// traits say (SchemeTraits: passive_by_design, linear_loop_model).
/// @throws ConfigError naming the allowed schemes if s.scheme is unknown.
void fill_analytic(const PressScenario& s, const PressSetup& setup, PressResult& r);

/// Runs one scenario built by build_press_setup(s) against `slave`, a slave simulating
/// setup.slave's world (the callers that link the server use server::WorldSlave; see
/// tests/support/press_world.hpp). The loop itself allocates nothing.
PressResult run_press(const PressScenario& s, const PressSetup& setup, SlaveSimulator& slave);

}  // namespace teleop::master
