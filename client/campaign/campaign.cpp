#include "client/campaign/campaign.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "client/campaign/results.hpp"
#include "client/control/bilateral_controller.hpp"
#include "client/control/scheme_traits.hpp"
#include "client/device/operator_model.hpp"
#include "client/net/delay_config.hpp"
#include "client/net/delay_params.hpp"
#include "common/harness/in_process.hpp"
#include "common/util/csv.hpp"

namespace teleop::campaign {

namespace {

using config::ConfigError;
using config::Node;

/// One axis a sweep may list: its key, what its values are and which RunParams field takes
/// them (a number, a whole number or a text field: one of the three is set).
struct Axis {
  const char* key;
  enum class Kind { kNumber, kInteger, kText } kind;
  double lo, hi;                     ///< range of a number
  std::vector<std::string> allowed;  ///< choices of a text ({}: any non-empty text)
  bool point, world;                 ///< models it applies to
  double RunParams::*number = nullptr;
  std::uint64_t RunParams::*integer = nullptr;
  std::string RunParams::*text = nullptr;

  void set(RunParams& p, const std::string& t, double v) const {
    if (number) p.*number = v;
    if (integer) p.*integer = static_cast<std::uint64_t>(v);
    if (text) p.*text = t;
  }
};

Axis number_axis(const char* key, double lo, double hi, bool point, bool world,
                 double RunParams::*field) {
  Axis a{key, Axis::Kind::kNumber, lo, hi, {}, point, world};
  a.number = field;
  return a;
}

/// An axis of a channel parameter's number `part` (client/net/delay_params.hpp): the table's
/// range times `scale` (1e3: an axis in ms); where the table excludes its lower end, the run's
/// check refuses it (check_run).
Axis channel_axis(const char* key, const char* param, std::size_t part, double scale,
                  double RunParams::*field) {
  const master::DelayPart& p = master::delay_param(param).parts.at(part);
  return number_axis(key, p.lo * scale, p.hi * scale, true, true, field);
}

Axis text_axis(const char* key, std::vector<std::string> allowed, bool point, bool world,
               std::string RunParams::*field) {
  Axis a{key, Axis::Kind::kText, 0.0, 0.0, std::move(allowed), point, world};
  a.text = field;
  return a;
}

/// Every axis, in expansion order (the last varies fastest).
const std::vector<Axis>& axes() {
  static const std::vector<Axis> a = [] {
    using P = RunParams;
    std::vector<Axis> v = {
        text_axis("scene", {}, false, true, &P::scene),
        text_axis("environment", {"sphere", "wall"}, true, false, &P::environment),
        number_axis("stiffness_n_per_m", 1.0, 1e6, true, false, &P::stiffness_n_per_m),
        number_axis("damping_ns_per_m", 0.0, 1e4, true, false, &P::damping_ns_per_m),
        text_axis("script", {"press-slip", "hold", "line", "circle", "step"}, true, true,
                  &P::script),
        text_axis("trajectory", {}, true, true, &P::trajectory),
        number_axis("press_depth_m", 0.0, 0.2, true, true, &P::press_depth_m),
        number_axis("tremor_m", 0.0, 0.01, true, true, &P::tremor_m),
        text_axis("scheme", scheme_labels(), true, true, &P::scheme),
        number_axis("gain", 0.0, 1e5, true, true, &P::gain),
        channel_axis("delay_ms", "delay", 0, 1e3, &P::delay_ms),
        channel_axis("jitter_ms", "jitter", 0, 1e3, &P::jitter_ms),
        channel_axis("loss", "loss", 0, 1.0, &P::loss),
        channel_axis("burst_p_gb", "burst_loss", 0, 1.0, &P::burst_p_gb),
        channel_axis("burst_p_bg", "burst_loss", 1, 1.0, &P::burst_p_bg),
        number_axis("max_force_n", 0.0, 1000.0, true, true, &P::max_force_n),
    };
    const master::DelayParam& seed_param = master::delay_param("seed");
    Axis seed{"seed", Axis::Kind::kInteger, seed_param.lo, seed_param.hi, {}, true, true};
    seed.integer = &P::seed;
    v.push_back(seed);
    return v;
  }();
  return a;
}

/// One value of an axis, as text (for text axes) and number.
struct Value {
  std::string text;
  double number = 0.0;
};

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

/// A scalar of axis `a` at `node` (field `field` of `parent`, for messages).
Value read_scalar(const Axis& a, const Node& parent, const std::string& field,
                  const YAML::Node& y) {
  if (!y.IsScalar()) parent.fail(field, "must be a single value");
  Value v;
  v.text = y.Scalar();
  if (a.kind == Axis::Kind::kText) {
    if (v.text.empty()) parent.fail(field, "'' is empty; a value is needed");
    if (!a.allowed.empty() &&
        std::find(a.allowed.begin(), a.allowed.end(), v.text) == a.allowed.end()) {
      parent.fail(field, "'" + v.text + "' is not one of " + join(a.allowed));
    }
    return v;
  }
  const std::string problem =
      config::number_problem(v.text, a.lo, a.hi, a.kind == Axis::Kind::kInteger);
  if (!problem.empty()) parent.fail(field, problem);
  v.number = std::stod(v.text);
  return v;
}

/// The values of axis `a` in mapping `m`: a scalar, a list, or {from, to, step}.
std::vector<Value> read_axis(const Axis& a, const Node& m) {
  const Node n = m.at(a.key);
  const YAML::Node& y = n.raw();
  std::vector<Value> out;
  if (y.IsSequence()) {
    if (y.size() == 0) m.fail(a.key, "is an empty list; give at least one value");
    for (std::size_t i = 0; i < y.size(); ++i) {
      out.push_back(read_scalar(a, m, std::string(a.key) + "[" + std::to_string(i) + "]", y[i]));
    }
  } else if (y.IsMap()) {
    if (a.kind == Axis::Kind::kText) m.fail(a.key, "a range {from, to, step} needs a number axis");
    n.reject_unknown_keys({"from", "to", "step"});
    const double from = n.number("from", a.lo, a.hi);
    const double to = n.number("to", from, a.hi);
    const double step = n.number("step", 1e-9, 1e9);
    const double count = std::floor((to - from) / step + 1e-9) + 1.0;
    if (count > static_cast<double>(kMaxRuns)) n.fail("step", "gives more than 10^7 values");
    for (long long i = 0; i < static_cast<long long>(count); ++i) {
      Value v;
      v.number = from + static_cast<double>(i) * step;
      v.text = format_number(v.number);
      out.push_back(v);
    }
  } else {
    out.push_back(read_scalar(a, m, a.key, y));
  }
  return out;
}

std::set<std::string> axis_keys() {
  std::set<std::string> k;
  for (const Axis& a : axes()) k.insert(a.key);
  return k;
}

/// Checks that every axis `m` lists applies to the model.
void check_axes_apply(const Node& m, SlaveModel model) {
  for (const Axis& a : axes()) {
    if (!m.has(a.key)) continue;
    const bool ok = model == SlaveModel::kPoint ? a.point : a.world;
    if (!ok) {
      m.fail(a.key, std::string("does not apply to model '") +
                        (model == SlaveModel::kPoint ? "point" : "world") + "'");
    }
  }
}

/// Expands one sweep (over the defaults) into `out`.
void expand_sweep(const Node& sweep, const Node& defaults, Campaign& c) {
  sweep.reject_unknown_keys([] {
    auto k = axis_keys();
    k.insert("name");
    return k;
  }());
  check_axes_apply(sweep, c.model);
  const std::string name = sweep.string("name");
  std::vector<std::pair<const Axis*, std::vector<Value>>> lists;
  double total = 1.0;
  for (const Axis& a : axes()) {
    if (sweep.has(a.key)) {
      lists.emplace_back(&a, read_axis(a, sweep));
    } else if (defaults.defined() && defaults.has(a.key)) {
      lists.emplace_back(&a, read_axis(a, defaults));
    } else {
      continue;
    }
    total *= static_cast<double>(lists.back().second.size());
  }
  if (total + static_cast<double>(c.runs.size()) > static_cast<double>(kMaxRuns)) {
    sweep.fail("name", "'" + name + "' expands the campaign past 10^7 runs");
  }
  std::vector<std::size_t> at(lists.size(), 0);
  for (std::size_t n = 0; n < static_cast<std::size_t>(total); ++n) {
    RunParams p;
    p.id = c.runs.size();
    p.sweep = name;
    if (c.model == SlaveModel::kWorld) p.environment.clear();
    for (std::size_t i = 0; i < lists.size(); ++i) {
      const Value& v = lists[i].second[at[i]];
      lists[i].first->set(p, v.text, v.number);
    }
    c.runs.push_back(p);
    // the last axis varies fastest
    for (std::size_t i = lists.size(); i-- > 0;) {
      if (++at[i] < lists[i].second.size()) break;
      at[i] = 0;
    }
  }
}

/// The controller and both channels of `p` pass their own checks (messages name the run).
void check_run(const Node& root, const RunParams& p) {
  try {
    const SchemeLaw law = scheme_law(p.scheme);
    master::ControllerParams cp;
    cp.scheme = law.scheme;
    cp.tdpa_base = law.tdpa_base;
    cp.validate();
    master::DelayConfig d;
    d.delay_s = p.delay_ms * 1e-3;
    d.jitter_s = p.jitter_ms * 1e-3;
    d.loss_probability = p.loss;
    d.burst_loss = p.burst_p_gb > 0.0;
    d.burst_p_good_to_bad = p.burst_p_gb;
    d.burst_p_bad_to_good = p.burst_p_bg;
    d.validate();
  } catch (const ConfigError& e) {
    root.fail("sweeps", "run " + std::to_string(p.id) + " (sweep '" + p.sweep + "'): " + e.what());
  }
}

/// `name` as a path: as it is when absolute, else relative to the campaign file's folder.
std::string beside(const Campaign& c, const std::string& name) {
  const std::filesystem::path p(name);
  return p.is_absolute() ? name : (std::filesystem::path(c.file).parent_path() / p).string();
}

/// Loads every scene and recorded trajectory the runs name, once each.
void load_inputs(const Node& root, Campaign& c) {
  for (const RunParams& p : c.runs) {
    if (p.trajectory.empty() || c.trajectories.count(p.trajectory)) continue;
    c.trajectories[p.trajectory] = std::make_shared<const std::vector<master::ReplaySample>>(
        master::load_replay_csv(beside(c, p.trajectory)));
  }
  for (const RunParams& p : c.runs) {
    if (c.model != SlaveModel::kWorld) break;
    if (p.scene.empty()) {
      root.fail("sweeps", "run " + std::to_string(p.id) + " (sweep '" + p.sweep +
                              "') names no scene; model 'world' needs `scene:`");
    }
    if (c.scenes.count(p.scene)) continue;
    c.scenes[p.scene] = harness::load_scene_model(beside(c, p.scene));
  }
}

Measures read_measures(const Node& root) {
  Measures m;
  if (!root.has("measure")) return m;
  const YAML::Node& y = root.at("measure").raw();
  if (!y.IsSequence() || y.size() == 0) {
    root.fail("measure",
              "must be a list of: stability, errors, transparency, energy, faults, "
              "channels");
  }
  m = Measures{false, false, false, false, false, false};
  for (std::size_t i = 0; i < y.size(); ++i) {
    const std::string s = y[i].IsScalar() ? y[i].Scalar() : "";
    const std::string field = "measure[" + std::to_string(i) + "]";
    if (s == "stability")
      m.stability = true;
    else if (s == "errors")
      m.errors = true;
    else if (s == "transparency")
      m.transparency = true;
    else if (s == "energy")
      m.energy = true;
    else if (s == "faults")
      m.faults = true;
    else if (s == "channels")
      m.channels = true;
    else
      root.fail(field, "'" + s +
                           "' is not one of stability, errors, transparency, energy, "
                           "faults, channels");
  }
  return m;
}

Campaign parse_root(const Node& root, const std::string& file) {
  if (root.empty_document() || !root.is_map()) {
    throw ConfigError(file + ": a campaign is a mapping with `name:` and `sweeps:`");
  }
  root.reject_unknown_keys(
      {"name", "model", "duration_s", "homing_s", "measure", "defaults", "sweeps"});
  Campaign c;
  c.file = file;
  c.name = root.string("name");
  for (char ch : c.name) {
    if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '-' && ch != '_' && ch != '.') {
      root.fail("name", "'" + c.name + "' may hold only letters, digits, '-', '_' and '.'");
    }
  }
  c.model = root.choice_or("model", "point", {"point", "world"}) == "world" ? SlaveModel::kWorld
                                                                            : SlaveModel::kPoint;
  c.duration_s = root.number_or("duration_s", 0.0, 0.0, 3600.0);
  c.homing_s = root.number_or("homing_s", 1.5, 0.0, 60.0);
  c.measures = read_measures(root);
  const Node defaults = root.child("defaults");
  if (defaults.defined()) {
    defaults.reject_unknown_keys(axis_keys());
    check_axes_apply(defaults, c.model);
  }
  const Node sweeps = root.at("sweeps");
  if (!sweeps.is_sequence() || sweeps.size() == 0) {
    root.fail("sweeps", "must be a non-empty list of sweeps (mappings of axes)");
  }
  std::set<std::string> names;
  for (std::size_t i = 0; i < sweeps.size(); ++i) {
    const Node s = sweeps.at(i);
    if (!s.is_map()) root.fail("sweeps[" + std::to_string(i) + "]", "must be a mapping of axes");
    expand_sweep(s, defaults, c);
    if (!names.insert(s.string("name")).second) {
      s.fail("name", "'" + s.string("name") + "' names two sweeps");
    }
  }
  for (const RunParams& p : c.runs) {
    check_run(root, p);
    const bool endless =
        p.trajectory.empty() && (p.script == "hold" || p.script == "circle" || p.script == "step");
    if (endless && c.duration_s <= 0.0) {
      root.fail("duration_s", "is 0 but sweep '" + p.sweep + "' runs script '" + p.script +
                                  "', which has no end: give a length in (0, 3600]");
    }
  }
  load_inputs(root, c);
  return c;
}

}  // namespace

const std::vector<std::string>& scheme_labels() { return master::scheme_variant_labels(); }

SchemeLaw scheme_law(const std::string& label) {
  master::ControllerParams p;
  master::apply_scheme_variant(label, p);
  return {p.scheme, p.tdpa_base, !master::scheme_traits(p).position_based};
}

Campaign load_campaign(const std::string& file) {
  config::require_regular_file(file, "campaign");
  return parse_root(Node::load_file(file), file);
}

Campaign parse_campaign(const std::string& text, const std::string& file) {
  return parse_root(Node::parse(text, file), file);
}

std::string campaign_digest(const Campaign& c) {
  // FNV-1a over a canonical text of everything that decides the rows
  std::ostringstream s;
  s << c.name << '\n'
    << (c.model == SlaveModel::kPoint ? "point" : "world") << '\n'
    << format_number(c.duration_s) << '\n'
    << format_number(c.homing_s) << '\n'
    << results_header(c) << '\n';
  for (const RunParams& p : c.runs) s << parameter_cells(c, p) << '\n';
  for (const auto& [name, model] : c.scenes) {
    std::ifstream in(harness::scene_file(*model), std::ios::binary);
    s << name << '\n' << in.rdbuf() << '\n';
  }
  for (const auto& [name, samples] : c.trajectories) {
    s << name << '\n';
    for (const master::ReplaySample& r : *samples) {
      s << format_number(r.time_s) << ' ' << format_number(r.position_m.x()) << ' '
        << format_number(r.position_m.y()) << ' ' << format_number(r.position_m.z()) << ' '
        << format_number(r.orientation.w()) << ' ' << format_number(r.orientation.x()) << ' '
        << format_number(r.orientation.y()) << ' ' << format_number(r.orientation.z()) << '\n';
    }
  }
  std::uint64_t h = 1469598103934665603ull;
  for (const unsigned char ch : s.str()) {
    h ^= ch;
    h *= 1099511628211ull;
  }
  char buf[17];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

}  // namespace teleop::campaign
