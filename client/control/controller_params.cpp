#include "client/control/controller_params.hpp"

#include <algorithm>
#include <cstdio>
#include <set>
#include <type_traits>

#include "client/control/bilateral_controller.hpp"

namespace teleop::master {

using config::ConfigError;

namespace {

/// The value type T of a member pointer T C::*.
template <class M>
struct member_value;
template <class T, class C>
struct member_value<T C::*> {
  using type = T;
};

/// The field of `p` that `field` names, if it holds a T; else nullptr. P is ControllerParams or
/// const ControllerParams.
template <class T, class P>
auto* field_of(const ControllerParam::Field& field, P& p) {
  using Out = std::conditional_t<std::is_const_v<P>, const T, T>;
  Out* out = nullptr;
  std::visit(
      [&](auto member) {
        using M = decltype(member);
        if constexpr (std::is_same_v<M, T ControllerParams::*>) {
          out = &(p.*member);
        } else if constexpr (std::is_same_v<M, T WorkspaceMap::*>) {
          out = &(p.workspace.*member);
        }
      },
      field);
  return out;
}

std::string joined(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ", ") + n;
  return s;
}

/// The key's mapping ("" at the top, else the part before the dot) and its name in it.
std::pair<std::string, std::string> split_key(const std::string& key) {
  const auto dot = key.find('.');
  if (dot == std::string::npos) return {"", key};
  return {key.substr(0, dot), key.substr(dot + 1)};
}

/// The names the table allows in `section` ("" for the top: its own keys and the sections).
std::set<std::string> names_in(const std::vector<ControllerParam>& table,
                               const std::string& section) {
  std::set<std::string> names;
  for (const ControllerParam& d : table) {
    const auto [s, name] = split_key(d.key);
    if (section.empty()) names.insert(s.empty() ? name : s);
    if (!section.empty() && s == section) names.insert(name);
  }
  return names;
}

}  // namespace

ParamKind ControllerParam::kind() const {
  return std::visit(
      [](auto member) {
        using T = typename member_value<decltype(member)>::type;
        if constexpr (std::is_same_v<T, double>) return ParamKind::kNumber;
        if constexpr (std::is_same_v<T, bool>) return ParamKind::kBool;
        if constexpr (std::is_same_v<T, std::string>) return ParamKind::kChoice;
        return ParamKind::kPoint;
      },
      field);
}

double ControllerParam::number(const ControllerParams& p) const {
  const double* v = field_of<double>(field, p);
  return v != nullptr ? *v : 0.0;
}

void ControllerParam::set_number(ControllerParams& p, double v) const {
  if (double* f = field_of<double>(field, p)) *f = v;
}

std::string ControllerParam::text(const ControllerParams& p) const {
  switch (kind()) {
    case ParamKind::kNumber:
      return param_number_text(number(p));
    case ParamKind::kBool:
      return *field_of<bool>(field, p) ? "true" : "false";
    case ParamKind::kChoice:
      return *field_of<std::string>(field, p);
    case ParamKind::kPoint: {
      const Eigen::Vector3d& x = *field_of<Eigen::Vector3d>(field, p);
      return "[" + param_number_text(x.x()) + ", " + param_number_text(x.y()) + ", " +
             param_number_text(x.z()) + "]";
    }
  }
  return "";
}

std::string ControllerParam::allowed_text() const {
  const std::string range = "[" + param_number_text(lo) + ", " + param_number_text(hi) + "]";
  switch (kind()) {
    case ParamKind::kNumber:
      return range;
    case ParamKind::kBool:
      return "true, false";
    case ParamKind::kChoice:
      return joined(choices);
    case ParamKind::kPoint:
      return "each in " + range;
  }
  return "";
}

std::string ControllerParam::flag_help() const {
  const std::string prefix = scheme.empty() ? "" : scheme + ": ";
  switch (kind()) {
    case ParamKind::kBool:
      return prefix + switch_help;
    case ParamKind::kChoice:
      return prefix + help;
    case ParamKind::kNumber:
    case ParamKind::kPoint:
      break;
  }
  return prefix + help + " [" + unit + "], " + allowed_text();
}

void ControllerParam::check(const ControllerParams& p) const {
  switch (kind()) {
    case ParamKind::kNumber:
      config::check_range("controller", key, number(p), lo, hi);
      return;
    case ParamKind::kBool:
      return;
    case ParamKind::kChoice: {
      const std::string& v = *field_of<std::string>(field, p);
      if (std::find(choices.begin(), choices.end(), v) == choices.end()) {
        throw ConfigError("controller: " + key + " '" + v +
                          "' is unknown (allowed: " + joined(choices) + ")");
      }
      return;
    }
    case ParamKind::kPoint: {
      const Eigen::Vector3d& x = *field_of<Eigen::Vector3d>(field, p);
      for (int i = 0; i < 3; ++i) {
        config::check_range("controller", key + "[" + std::to_string(i) + "]", x[i], lo, hi);
      }
      return;
    }
  }
}

void ControllerParam::read(const config::Node& node, ControllerParams& p) const {
  const auto [section, name] = split_key(key);
  if (!section.empty() && !node.has(section)) return;
  const config::Node n = section.empty() ? node : node.at(section);
  if (!n.has(name)) return;
  switch (kind()) {
    case ParamKind::kNumber:
      *field_of<double>(field, p) = n.number(name, lo, hi);
      return;
    case ParamKind::kBool:
      *field_of<bool>(field, p) = n.boolean_or(name, false);
      return;
    case ParamKind::kChoice:
      *field_of<std::string>(field, p) = n.choice(name, choices);
      return;
    case ParamKind::kPoint: {
      const std::vector<double> x = n.numbers(name, 3, lo, hi);
      *field_of<Eigen::Vector3d>(field, p) = Eigen::Vector3d(x[0], x[1], x[2]);
      return;
    }
  }
}

void ControllerParam::apply_flag(const std::string& value, ControllerParams& p) const {
  switch (kind()) {
    case ParamKind::kNumber:
      *field_of<double>(field, p) = config::parse_number(flag, value, lo, hi);
      return;
    case ParamKind::kBool:
      *field_of<bool>(field, p) = switch_sets;
      return;
    case ParamKind::kChoice:
      if (std::find(choices.begin(), choices.end(), value) == choices.end()) {
        throw ConfigError("command line: " + flag + " '" + value + "' is not one of {" +
                          joined(choices) + "}");
      }
      *field_of<std::string>(field, p) = value;
      return;
    case ParamKind::kPoint: {
      const std::vector<double> los(3, lo), his(3, hi);
      const std::vector<double> x = config::parse_numbers(flag, value, 3, los, his);
      *field_of<Eigen::Vector3d>(field, p) = Eigen::Vector3d(x[0], x[1], x[2]);
      return;
    }
  }
}

const std::vector<ControllerParam>& common_controller_params() {
  using P = ControllerParams;
  using W = WorkspaceMap;
  static const std::vector<ControllerParam> table = {
      {.key = "scheme",
       .flag = "--scheme",
       .help = "bilateral control scheme (docs/control.md)",
       .field = &P::scheme,
       .choices = controller_names()},
      {.key = "slave_stiffness_n_per_m",
       .flag = "--kps",
       .unit = "N/m",
       .help = "slave position gain K_ps",
       .field = &P::slave_stiffness_n_per_m,
       .hi = 1e6},
      {.key = "master_stiffness_n_per_m",
       .flag = "--kpm",
       .unit = "N/m",
       .help = "master position gain K_pm (0 = transparent choice alpha beta K_ps; clamped to the "
               "device's max stiffness)",
       .field = &P::master_stiffness_n_per_m,
       .hi = 1e6},
      {.key = "master_damping_ns_per_m",
       .flag = "--bm",
       .unit = "N s/m",
       .help = "master damping B_m (clamped to the device's max damping)",
       .field = &P::master_damping_ns_per_m,
       .hi = 1e4},
      {.key = "force_gain",
       .flag = "--force-gain",
       .unit = "-",
       .help = "force-position reflection gain K_f",
       .field = &P::force_gain,
       .hi = 100.0},
      {.key = "max_force_n",
       .flag = "--max-force",
       .unit = "N",
       .help = "device force saturation (0 = the device's peak force)",
       .field = &P::max_force_n,
       .hi = 1e4},
      {.key = "send_velocity",
       .help = "command the mapped master velocity too",
       .field = &P::send_velocity},
      {.key = "contact_damping_ramp_s",
       .unit = "s",
       .help = "force-position and model-mediated: time to ramp B_m in at contact and out after it",
       .field = &P::contact_damping_ramp_s,
       .lo = 1e-4,
       .hi = 10.0},
      {.key = "workspace.offset_m",
       .unit = "m",
       .help = "slave point [x, y, z] of the master origin",
       .field = &W::offset_m,
       .lo = -1e3,
       .hi = 1e3},
      {.key = "workspace.position_scale",
       .flag = "--position-scale",
       .unit = "-",
       .help = "alpha: slave metres per master metre",
       .field = &W::position_scale,
       .lo = 1e-3,
       .hi = 1e3},
      {.key = "workspace.force_scale",
       .flag = "--force-scale",
       .unit = "-",
       .help = "beta: master newtons per slave newton",
       .field = &W::force_scale,
       .lo = 1e-3,
       .hi = 1e3},
  };
  return table;
}

void ControllerParams::validate() const {
  for (const ControllerParam& d : controller_param_table()) d.check(*this);
}

ControllerParams controller_params_from_yaml(const config::Node& node) {
  ControllerParams p;
  if (!node.defined()) return p;
  const std::vector<ControllerParam>& table = controller_param_table();
  const std::set<std::string> top = names_in(table, "");
  node.reject_unknown_keys(top);
  for (const std::string& name : top) {
    const std::set<std::string> inner = names_in(table, name);
    if (!inner.empty() && node.has(name)) node.at(name).reject_unknown_keys(inner);
  }
  for (const ControllerParam& d : table) d.read(node, p);
  p.validate();
  return p;
}

std::string controller_params_markdown() {
  const ControllerParams defaults;
  std::string md =
      "| key | flag | unit | default | range | help |\n"
      "|---|---|---|---|---|---|\n";
  for (const ControllerParam& d : controller_param_table()) {
    std::string flag = d.flag.empty() ? "" : "`" + d.flag + "`";
    if (!d.flag.empty() && d.kind() == ParamKind::kBool) {
      flag += std::string(" (sets ") + (d.switch_sets ? "true" : "false") + ")";
    }
    const std::string help = (d.scheme.empty() ? "" : d.scheme + ": ") + d.help;
    md += "| `" + d.key + "` | " + flag + " | " + d.unit + " | " + d.text(defaults) + " | " +
          d.allowed_text() + " | " + help + " |\n";
  }
  return md;
}

}  // namespace teleop::master
