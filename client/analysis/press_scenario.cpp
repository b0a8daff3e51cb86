#include "client/analysis/press_scenario.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "client/control/scheme_traits.hpp"

namespace teleop::master {

namespace {
constexpr double kSphereRadius = 0.25;  // [m]
constexpr double kToolRadius = 0.05;    // [m]

/// The controller's law as the scenario sets it (scheme and its own parameters; the gains and
/// the workspace are set by build_press_setup()).
ControllerParams scenario_law(const PressScenario& s) {
  ControllerParams p;
  p.scheme = s.scheme;
  p.tdpa_base = s.tdpa_base;
  p.wave_impedance_ns_per_m = s.wave_impedance_ns_per_m;
  p.wave_matched = s.wave_matched;
  return p;
}
}  // namespace

PressSetup build_press_setup(const PressScenario& s) {
  PressSetup out;
  // operator: the Fig. 13 script around the master origin (the touching point)
  out.device.hand = s.hand;
  out.device.script = press_slip_script(Eigen::Vector3d::Zero(), s.press_depth_m);
  out.device.script.tremor_amplitude_m = s.tremor_m;

  // slave: point tool tracking the command; object on the floor
  sim::ToolModel& sp = out.slave;
  sp.radius_m = kToolRadius;
  sim::Obstacle floor;
  floor.kind = sim::Obstacle::Kind::kPlane;
  floor.offset_m = 0.0;
  floor.id = 0;
  sp.add(floor);
  sim::Obstacle obj;
  obj.stiffness_n_per_m = s.env_stiffness_n_per_m;
  obj.damping_ns_per_m = s.env_damping_ns_per_m;
  obj.id = 1;
  if (s.environment == Environment::kSphere) {
    obj.kind = sim::Obstacle::Kind::kSphere;
    obj.centre_m = Eigen::Vector3d(0.0, 0.0, kSphereRadius);
    obj.radius_m = kSphereRadius;
  } else {
    obj.kind = sim::Obstacle::Kind::kPlane;
    obj.normal = Eigen::Vector3d::UnitZ();
    obj.offset_m = 2.0 * kSphereRadius;  // a stiff surface at the sphere's top height
  }
  sp.add(obj);

  // loop
  LoopbackConfig& c = out.loop;
  c.controller = scenario_law(s);
  c.controller.workspace.offset_m = Eigen::Vector3d(0.0, 0.0, 2.0 * kSphereRadius + kToolRadius);
  if (press_position_like(s)) {
    const double k = s.gain > 0.0 ? s.gain : 400.0;
    c.controller.slave_stiffness_n_per_m = k;
    c.controller.master_stiffness_n_per_m = k;
  } else {
    c.controller.slave_stiffness_n_per_m = 400.0;
    c.controller.force_gain = s.gain > 0.0 ? s.gain : 1.0;
  }
  sp.kp_n_per_m = c.controller.slave_stiffness_n_per_m;
  c.forward.delay_s = c.backward.delay_s = s.one_way_delay_s;
  c.forward.jitter_s = c.backward.jitter_s = s.jitter_s;
  c.forward.seed = s.seed;
  c.backward.seed = s.seed + 1;
  c.safety_enabled = s.safety;
  c.duration_s = s.duration_s > 0.0 ? s.duration_s : script_duration_s(out.device.script) + 3.0;
  return out;
}

bool press_position_like(const PressScenario& s) {
  return scheme_traits(scenario_law(s)).position_based;
}

LoopModel press_loop_model(const PressScenario& s, const PressSetup& setup) {
  LoopModel m;
  m.position_position = press_position_like(s);
  const DeviceSpec& spec = setup.device.spec;
  const ControllerParams& cp = setup.loop.controller;
  m.master_mass_kg = setup.device.device_mass_kg + setup.device.hand.mass_kg;
  m.master_damping_ns_per_m = setup.device.device_damping_ns_per_m +
                              setup.device.hand.damping_ns_per_m +
                              std::min(cp.master_damping_ns_per_m, spec.max_damping_ns_per_m);
  m.hand_stiffness_n_per_m = setup.device.hand.stiffness_n_per_m;
  const double k_auto =
      cp.workspace.position_scale * cp.workspace.force_scale * cp.slave_stiffness_n_per_m;
  m.master_gain_n_per_m =
      std::min(cp.master_stiffness_n_per_m > 0.0 ? cp.master_stiffness_n_per_m : k_auto,
               spec.max_stiffness_n_per_m);
  m.force_gain = cp.workspace.position_scale * cp.workspace.force_scale * cp.force_gain;
  m.slave_mass_kg = setup.slave.mass_kg;
  m.slave_kp_n_per_m = cp.slave_stiffness_n_per_m;
  m.slave_kd_ns_per_m = setup.slave.kd_ns_per_m;
  m.slave_damping_ns_per_m = setup.slave.linear_damping_ns_per_m;
  m.env_stiffness_n_per_m = s.env_stiffness_n_per_m;
  m.env_damping_ns_per_m = s.env_damping_ns_per_m;
  return m;
}

void fill_analytic(const PressScenario& s, const PressSetup& setup, PressResult& r) {
  const SchemeTraits traits = scheme_traits(scenario_law(s));
  r.passive_scheme = traits.passive_by_design;
  // no linear model: the scheme's theory is stability at every delay
  if (!traits.linear_loop_model) {
    r.analytic_margin_s = std::numeric_limits<double>::infinity();
    r.analytic_stable = true;
    return;
  }
  const LoopModel m = press_loop_model(s, setup);
  r.analytic_margin_s = task_delay_margin(m).one_way_s;
  r.analytic_stable = task_stable_at(m, s.one_way_delay_s);
}

void fill_metrics(const SessionMetrics& m, PressResult& r) {
  r.verdict = m.verdict();
  r.reason = m.verdict_reason();
  r.position_error_rms_m = m.position_error_rms_m();
  r.force_error_rms_n = m.force_error_rms_n();
  r.max_device_force_n = m.max_device_force_n();
  r.energy_min_j = m.energy_min_j();
  r.contact_time_s = m.contact_time_s();
  r.free_force_mean_n = m.free_force_mean_n();
  r.free_force_p99_n = m.free_force_p99_n();
  r.felt_force_ratio = m.felt_force_ratio();
  r.felt_stiffness_n_per_m = m.felt_stiffness_n_per_m();
  r.environment_stiffness_n_per_m = m.environment_stiffness_n_per_m();
  r.stiffness_ratio = m.stiffness_ratio();
}

PressResult run_press(const PressScenario& s, const PressSetup& setup, SlaveSimulator& slave) {
  SimulatedDevice device(setup.device);
  LoopbackSession session(setup.loop, device, slave);
  session.start();
  double max_ctrl = 0.0;
  double min_observer = 0.0;
  while (session.step()) {
    max_ctrl = std::max(max_ctrl, session.controller_force_n().norm());
    min_observer = std::min(min_observer, session.controller().passivity_status().observer_j);
  }
  PressResult r;
  fill_metrics(session.metrics(), r);
  r.max_controller_force_n = max_ctrl;
  r.safety_cut = session.safety().cut();
  fill_analytic(s, setup, r);
  r.passivity_dissipated_j =
      session.controller().passivity_status().dissipated_j + slave.sample().passivity_dissipated_j;
  r.min_observer_j = min_observer;
  return r;
}

}  // namespace teleop::master
