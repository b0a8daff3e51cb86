#include "client/campaign/results.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <memory>

#include "client/analysis/press_scenario.hpp"
#include "common/dds/contact_point.hpp"
#include "common/harness/in_process.hpp"
#include "common/util/csv.hpp"

namespace teleop::campaign {

namespace {

using harness::InProcessSlave;
using master::LoopbackSession;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

/// A number cell: shortest round-trip text, "nan", "inf" or "-inf".
std::string num(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  return format_number(v);
}

/// A text cell: commas and blanks would break the table.
std::string text(std::string s) {
  std::replace(s.begin(), s.end(), ',', ';');
  std::replace(s.begin(), s.end(), ' ', '_');
  std::replace(s.begin(), s.end(), '\n', '_');
  return s.empty() ? "-" : s;
}

/// What one session measured.
struct Outcome {
  std::string verdict = "error";
  int verdict_code = -1;
  std::string reason;
  // stability
  int theory_stable = -1;  ///< the linear model's exact verdict (point; -1 where none)
  double analytic_margin_ms = kNan;
  double unstable_since_s = kNan, oscillating_windows = 0, saturated_time_s = 0;
  // errors
  double position_error_rms_mm = kNan, position_error_max_mm = kNan, force_error_rms_n = kNan,
         max_device_force_n = kNan, max_controller_force_n = kNan, contact_time_s = kNan,
         mean_contact_force_n = kNan;
  // transparency
  double free_force_mean_n = kNan, free_force_p99_n = kNan, felt_force_ratio = kNan,
         felt_stiffness_n_per_m = kNan, environment_stiffness_n_per_m = kNan,
         stiffness_ratio = kNan;
  // energy
  double energy_j = kNan, energy_min_j = kNan, passivity_dissipated_j = kNan,
         over_rating_time_s = kNan;
  // faults
  double nonfinite_samples = kNan, link_lost_time_s = kNan, watchdog_trips = kNan,
         world_faults = kNan;
  int safety_cut = -1;
  // channels
  double forward_loss = kNan, backward_loss = kNan, forward_delay_p99_ms = kNan,
         backward_delay_p99_ms = kNan;
};

/// Emits the outcome's cells (or their names) in the table's order.
template <class Add>
void outcome_cells(const Measures& m, const Outcome& o, Add&& add) {
  add("verdict", o.verdict);
  add("verdict_code", std::to_string(o.verdict_code));
  add("reason", text(o.reason));
  if (m.stability) {
    add("theory_stable", std::to_string(o.theory_stable));
    add("analytic_margin_ms", num(o.analytic_margin_ms));
    add("unstable_since_s", num(o.unstable_since_s));
    add("oscillating_windows", num(o.oscillating_windows));
    add("saturated_time_s", num(o.saturated_time_s));
  }
  if (m.errors) {
    add("position_error_rms_mm", num(o.position_error_rms_mm));
    add("position_error_max_mm", num(o.position_error_max_mm));
    add("force_error_rms_n", num(o.force_error_rms_n));
    add("max_device_force_n", num(o.max_device_force_n));
    add("max_controller_force_n", num(o.max_controller_force_n));
    add("contact_time_s", num(o.contact_time_s));
    add("mean_contact_force_n", num(o.mean_contact_force_n));
  }
  if (m.transparency) {
    add("free_force_mean_n", num(o.free_force_mean_n));
    add("free_force_p99_n", num(o.free_force_p99_n));
    add("felt_force_ratio", num(o.felt_force_ratio));
    add("felt_stiffness_n_per_m", num(o.felt_stiffness_n_per_m));
    add("environment_stiffness_n_per_m", num(o.environment_stiffness_n_per_m));
    add("stiffness_ratio", num(o.stiffness_ratio));
  }
  if (m.energy) {
    add("energy_j", num(o.energy_j));
    add("energy_min_j", num(o.energy_min_j));
    add("passivity_dissipated_j", num(o.passivity_dissipated_j));
    add("over_rating_time_s", num(o.over_rating_time_s));
  }
  if (m.faults) {
    add("safety_cut", std::to_string(o.safety_cut));
    add("nonfinite_samples", num(o.nonfinite_samples));
    add("link_lost_time_s", num(o.link_lost_time_s));
    add("watchdog_trips", num(o.watchdog_trips));
    add("world_faults", num(o.world_faults));
  }
  if (m.channels) {
    add("forward_loss", num(o.forward_loss));
    add("backward_loss", num(o.backward_loss));
    add("forward_delay_p99_ms", num(o.forward_delay_p99_ms));
    add("backward_delay_p99_ms", num(o.backward_delay_p99_ms));
  }
}

/// Emits the parameter cells (or their names).
template <class Add>
void param_cells(const Campaign& c, const RunParams& p, Add&& add) {
  add("run_id", run_name(p.id));
  add("sweep", p.sweep);
  add("model", c.model == SlaveModel::kPoint ? "point" : "world");
  add("scene", text(p.scene));
  add("environment", text(p.environment));
  add("stiffness_n_per_m", c.model == SlaveModel::kPoint ? num(p.stiffness_n_per_m) : "nan");
  add("damping_ns_per_m", c.model == SlaveModel::kPoint ? num(p.damping_ns_per_m) : "nan");
  add("script", p.script);
  add("trajectory", text(p.trajectory));
  add("press_depth_m", num(p.press_depth_m));
  add("tremor_m", num(p.tremor_m));
  add("scheme", p.scheme);
  add("gain", num(p.gain));
  add("delay_ms", num(p.delay_ms));
  add("jitter_ms", num(p.jitter_ms));
  add("loss", num(p.loss));
  add("burst_p_gb", num(p.burst_p_gb));
  add("burst_p_bg", num(p.burst_p_bg));
  add("max_force_n", num(p.max_force_n));
  add("seed", std::to_string(p.seed));
}

/// Joins cells with commas (names or values).
struct Joiner {
  bool names;
  std::string out;
  void operator()(const char* name, const std::string& value) {
    if (!out.empty()) out += ',';
    out += names ? std::string(name) : value;
  }
};

/// The channel impairment of `p`, one direction.
master::DelayConfig channel(const RunParams& p, std::uint64_t seed) {
  master::DelayConfig d;
  d.delay_s = p.delay_ms * 1e-3;
  d.jitter_s = p.jitter_ms * 1e-3;
  d.loss_probability = p.loss;
  d.burst_loss = p.burst_p_gb > 0.0;
  d.burst_p_good_to_bad = p.burst_p_gb;
  d.burst_p_bad_to_good = p.burst_p_bg;
  d.seed = seed;
  return d;
}

/// The operator script of `p`, as teleop_master builds it: press-slip around the master
/// origin (the contact point), the free-motion scripts 5 cm above it.
master::OperatorScript script_of(const RunParams& p) {
  if (p.script == "press-slip") {
    master::OperatorScript s = master::press_slip_script(Eigen::Vector3d::Zero(), p.press_depth_m);
    s.tremor_amplitude_m = p.tremor_m;
    return s;
  }
  master::OperatorScript s;
  s.kind = master::parse_script_kind(p.script);
  s.start_m = Eigen::Vector3d(0.0, 0.0, 0.05);
  s.line_end_m = s.start_m + Eigen::Vector3d(0.05, 0.0, 0.0);
  s.tremor_amplitude_m = p.tremor_m;
  return s;
}

/// The operator's device: the recorded trajectory of `p` if it names one, else the simulated
/// device with its script.
std::unique_ptr<master::HapticDevice> make_device(const Campaign& c, const RunParams& p,
                                                  const master::SimulatedDeviceParams& dp) {
  if (p.trajectory.empty()) return std::make_unique<master::SimulatedDevice>(dp);
  return std::make_unique<master::ReplayDevice>(*c.trajectories.at(p.trajectory), dp.spec);
}

/// Session length when the campaign gives none: the script's or the trajectory's length plus
/// `extra_s`, at least `at_least_s` [s].
double default_length_s(const Campaign& c, const RunParams& p,
                        const master::SimulatedDeviceParams& dp, double extra_s,
                        double at_least_s) {
  if (c.duration_s > 0.0) return c.duration_s;
  const double len = p.trajectory.empty() ? master::script_duration_s(dp.script)
                                          : c.trajectories.at(p.trajectory)->back().time_s;
  return std::max(at_least_s, len + extra_s);
}

/// Writes a 3-vector into row `i` of a channel.
void put3(std::vector<double>& d, std::size_t i, const Eigen::Vector3d& v) {
  d[3 * i] = v.x();
  d[3 * i + 1] = v.y();
  d[3 * i + 2] = v.z();
}

/// Records the cycle just stepped into row t.size of `t` (nothing past its capacity); `s` is
/// the slave's sample.
void record_cycle(const LoopbackSession& session, const SlaveSample& s, RunTraces& t) {
  if (t.size >= t.capacity) {
    ++t.dropped;
    return;
  }
  const std::size_t i = t.size++;
  const master::MetricsSample& m = session.last_sample();
  auto* d = t.data;
  d[RunTraces::kTime][i] = session.time_s();
  d[RunTraces::kHoming][i] = session.cycle().homing() ? 1.0 : 0.0;
  put3(d[RunTraces::kMasterPosition], i, m.master_position_m);
  put3(d[RunTraces::kSlavePosition], i, s.position_m);
  put3(d[RunTraces::kCommandPosition], i, session.slave_command().position_m);
  put3(d[RunTraces::kControllerForce], i, session.controller_force_n());
  put3(d[RunTraces::kDeviceForce], i, session.device_force_n());
  put3(d[RunTraces::kContactForce], i, s.contact_force_n);
  put3(d[RunTraces::kContactAtMaster], i, session.slave_at_master().contact_force_n);
  d[RunTraces::kPenetration][i] = s.penetration_m;
  d[RunTraces::kDeformation][i] = s.deformation_m;
  d[RunTraces::kInContact][i] = s.in_contact ? 1.0 : 0.0;
  d[RunTraces::kSafetyScale][i] = m.safety_scale;
  d[RunTraces::kLinkOk][i] = m.link_ok ? 1.0 : 0.0;
}

/// Steps `session` to its end, keeping the largest force the controller asked for, and
/// records each cycle into `traces` (when given), sized first for `cycles` cycles.
void drive(LoopbackSession& session, const InProcessSlave& slave, Outcome& o, RunTraces* traces,
           double session_s, double dt_s) {
  if (traces != nullptr) traces->reserve(static_cast<std::size_t>(std::ceil(session_s / dt_s)) + 8);
  session.start();
  const SlaveSample& sample = slave.sample();  // the same object for the slave's lifetime
  double max_ctrl = 0.0;
  while (session.step()) {
    max_ctrl = std::max(max_ctrl, session.controller_force_n().norm());
    if (traces != nullptr) record_cycle(session, sample, *traces);
  }
  o.max_controller_force_n = max_ctrl;
}

/// The figures every model shares, from the finished session and its slave.
void collect(const LoopbackSession& session, const InProcessSlave& slave, Outcome& o) {
  const master::SessionMetrics& m = session.metrics();
  o.verdict = master::verdict_name(m.verdict());
  o.verdict_code = static_cast<int>(m.verdict());
  o.reason = m.verdict_reason();
  o.unstable_since_s = m.unstable_since_s() >= 0.0 ? m.unstable_since_s() : kNan;
  o.oscillating_windows = static_cast<double>(m.oscillating_windows());
  o.saturated_time_s = m.saturated_time_s();
  o.position_error_rms_mm = m.position_error_rms_m() * 1e3;
  o.position_error_max_mm = m.position_error_max_m() * 1e3;
  o.force_error_rms_n = m.force_error_rms_n();
  o.max_device_force_n = m.max_device_force_n();
  o.contact_time_s = m.contact_time_s();
  o.mean_contact_force_n = m.mean_contact_force_n();
  o.free_force_mean_n = m.free_force_mean_n();
  o.free_force_p99_n = m.free_force_p99_n();
  o.felt_force_ratio = m.felt_force_ratio();
  o.felt_stiffness_n_per_m = m.felt_stiffness_n_per_m();
  o.environment_stiffness_n_per_m = m.environment_stiffness_n_per_m();
  o.stiffness_ratio = m.stiffness_ratio();
  o.energy_j = m.energy_j();
  o.energy_min_j = m.energy_min_j();
  o.passivity_dissipated_j =
      session.controller().passivity_status().dissipated_j + slave.sample().passivity_dissipated_j;
  o.over_rating_time_s = m.over_rating_time_s();
  o.safety_cut = session.safety().cut() ? 1 : 0;
  o.nonfinite_samples = static_cast<double>(m.nonfinite_samples());
  o.link_lost_time_s = m.link_lost_time_s();
  o.watchdog_trips = static_cast<double>(slave.watchdog_trips());
  o.world_faults = static_cast<double>(slave.events_of(sim::EventKind::kFault));
  const master::ChannelReport f = session.forward().report(), b = session.backward().report();
  o.forward_loss = f.loss_fraction;
  o.backward_loss = b.loss_fraction;
  o.forward_delay_p99_ms = f.delay_p99_ms;
  o.backward_delay_p99_ms = b.delay_p99_ms;
}

/// The point model: teleop_bench delay's press task with this run's channels and device.
Outcome run_point(const Campaign& c, const RunParams& p, RunTraces* traces) {
  const SchemeLaw law = scheme_law(p.scheme);
  master::PressScenario s;
  s.scheme = law.scheme;
  s.tdpa_base = law.tdpa_base;
  const bool wall = p.environment == "wall";
  s.environment = wall ? master::Environment::kWall : master::Environment::kSphere;
  s.env_stiffness_n_per_m = p.stiffness_n_per_m;
  s.env_damping_ns_per_m = p.damping_ns_per_m > 0.0 ? p.damping_ns_per_m : (wall ? 50.0 : 5.0);
  s.gain = p.gain;
  s.one_way_delay_s = p.delay_ms * 1e-3;
  s.jitter_s = p.jitter_ms * 1e-3;
  s.press_depth_m = p.press_depth_m;
  s.tremor_m = p.tremor_m;
  s.duration_s = c.duration_s;
  s.seed = p.seed;
  master::PressSetup setup = master::build_press_setup(s);
  setup.loop.forward = channel(p, p.seed);
  setup.loop.backward = channel(p, p.seed + 1);
  if (p.max_force_n > 0.0) setup.device.spec.max_force_n = p.max_force_n;
  if (p.script != "press-slip") setup.device.script = script_of(p);
  // one pass of the script (or the trajectory) plus 3 s, as the press task's default
  setup.loop.duration_s = default_length_s(c, p, setup.device, 3.0, 0.0);
  const std::unique_ptr<master::HapticDevice> device = make_device(c, p, setup.device);
  const std::unique_ptr<InProcessSlave> slave = harness::make_tool_slave(
      setup.slave, setup.loop.controller.workspace.offset_m, setup.loop.dt_s);
  LoopbackSession session(setup.loop, *device, *slave);
  Outcome o;
  drive(session, *slave, o, traces, setup.loop.homing_s + setup.loop.duration_s, setup.loop.dt_s);
  collect(session, *slave, o);
  master::PressResult r;
  master::fill_analytic(s, setup, r);
  o.analytic_margin_ms = r.analytic_margin_s * 1e3;
  o.theory_stable = (r.passive_scheme || r.analytic_stable) ? 1 : 0;
  return o;
}

/// The world model: the scene stepped by the server's cycle, the master homing it first.
Outcome run_world(const Campaign& c, const RunParams& p, RunTraces* traces) {
  const harness::SceneModel& model = *c.scenes.at(p.scene);
  const double dt = 1.0 / harness::scene_physics_rate_hz(model);
  const std::unique_ptr<InProcessSlave> slave = harness::make_world_slave(model, dt);
  const SceneDescription scene = slave->describe_scene();
  master::SimulatedDeviceParams dp;
  dp.script = script_of(p);
  if (p.max_force_n > 0.0) dp.spec.max_force_n = p.max_force_n;
  master::LoopbackConfig loop;
  const SchemeLaw law = scheme_law(p.scheme);
  loop.controller.scheme = law.scheme;
  loop.controller.tdpa_base = law.tdpa_base;
  if (p.gain > 0.0 && law.force_gain) loop.controller.force_gain = p.gain;
  if (p.gain > 0.0 && !law.force_gain) {
    loop.controller.slave_stiffness_n_per_m = p.gain;
    loop.controller.master_stiffness_n_per_m = p.gain;
  }
  loop.controller.workspace.offset_m = dds::scene_contact_point(&scene, slave->sample().position_m);
  loop.forward = channel(p, p.seed);
  loop.backward = channel(p, p.seed + 1);
  loop.dt_s = dt;
  loop.homing_s = c.homing_s;
  // as teleop_master: the script's length plus 1 s after homing, at least 2 s
  loop.duration_s = default_length_s(c, p, dp, 1.0, 2.0);
  const std::unique_ptr<master::HapticDevice> device = make_device(c, p, dp);
  LoopbackSession session(loop, *device, *slave);
  Outcome o;
  drive(session, *slave, o, traces, loop.homing_s + loop.duration_s, loop.dt_s);
  collect(session, *slave, o);
  return o;
}

}  // namespace

std::string run_name(std::size_t id) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%07zu", id);
  return buf;
}

std::string results_header(const Campaign& c) {
  Joiner j{true, {}};
  param_cells(c, RunParams{}, j);
  outcome_cells(c.measures, Outcome{}, j);
  return j.out;
}

std::string parameter_cells(const Campaign& c, const RunParams& p) {
  Joiner j{false, {}};
  param_cells(c, p, j);
  return j.out;
}

namespace {
struct ChannelInfo {
  const char* name;
  std::size_t width;
};
constexpr ChannelInfo kChannels[RunTraces::kChannelCount] = {
    {"time_s", 1},
    {"homing", 1},
    {"master_position_m", 3},
    {"slave_position_m", 3},
    {"command_position_m", 3},
    {"controller_force_n", 3},
    {"device_force_n", 3},
    {"contact_force_n", 3},
    {"contact_force_at_master_n", 3},
    {"penetration_m", 1},
    {"deformation_m", 1},
    {"in_contact", 1},
    {"safety_scale", 1},
    {"link_ok", 1},
};
}  // namespace

const char* RunTraces::name(std::size_t channel) { return kChannels[channel].name; }
std::size_t RunTraces::width(std::size_t channel) { return kChannels[channel].width; }

void RunTraces::reserve(std::size_t cycles) {
  size = 0;
  dropped = 0;
  capacity = cycles;
  for (std::size_t k = 0; k < kChannelCount; ++k) data[k].assign(cycles * width(k), 0.0);
}

std::string run_one(const Campaign& c, const RunParams& p, RunTraces* traces) {
  Outcome o;
  try {
    o = c.model == SlaveModel::kPoint ? run_point(c, p, traces) : run_world(c, p, traces);
  } catch (const std::exception& e) {
    o = Outcome{};
    o.reason = e.what();
  }
  Joiner j{false, {}};
  param_cells(c, p, j);
  outcome_cells(c.measures, o, j);
  return j.out;
}

}  // namespace teleop::campaign
