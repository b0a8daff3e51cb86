// The controller's parameter table (client/control/controller_params.hpp): every entry's range
// and values enforced by the YAML loader, validate() and teleop_master's flags
// (client/control/controller_flags.hpp); the docs' table is the program's; each scheme's own
// parameters listed under it.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "client/control/bilateral_controller.hpp"
#include "client/control/controller_flags.hpp"
#include "client/control/controller_params.hpp"
#include "tests/support/config_error.hpp"

namespace {

using teleop::config::Node;
using teleop::config::range_text;
using teleop::master::controller_param_table;
using teleop::master::ControllerFlags;
using teleop::master::ControllerParam;
using teleop::master::ControllerParams;
using teleop::master::ParamKind;
using teleop::test::config_error_of;

/// A number written so that it reads back exactly.
std::string exact(double v) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

/// Just below lo and just above hi.
double below(double lo) { return lo - std::max(std::abs(lo), 1.0) * 1e-6; }
double above(double hi) { return hi + std::max(std::abs(hi), 1.0) * 1e-6; }

/// `controller: {KEY: VALUE}` with a dotted key as a nested mapping.
std::string controller_yaml(const std::string& key, const std::string& value) {
  const auto dot = key.find('.');
  if (dot == std::string::npos) return "controller: {" + key + ": " + value + "}";
  return "controller: {" + key.substr(0, dot) + ": {" + key.substr(dot + 1) + ": " + value + "}}";
}

/// Loads `controller: {KEY: VALUE}` from a file named ctl.yaml.
ControllerParams load(const std::string& key, const std::string& value) {
  return teleop::master::controller_params_from_yaml(
      Node::parse(controller_yaml(key, value), "ctl.yaml").at("controller"));
}

/// The message of loading KEY: VALUE ("" if it loads).
std::string yaml_error(const std::string& key, const std::string& value) {
  return config_error_of([&] { load(key, value); });
}

/// Parses `args` with the controller flags only and applies them over `p`. Returns the exit
/// status of parse_command_line (-1: parsed) and puts what it printed to stderr in `err`.
int parse_flags(const std::vector<std::string>& args, ControllerParams& p, std::string& err) {
  CLI::App app{"prog"};
  ControllerFlags f;
  teleop::master::add_controller_flags(app, f);
  std::vector<std::string> words = {"prog"};
  words.insert(words.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  testing::internal::CaptureStderr();
  const int status =
      teleop::config::parse_command_line(app, "prog", static_cast<int>(argv.size()), argv.data());
  err = testing::internal::GetCapturedStderr();
  if (status < 0) {
    err = config_error_of([&] { teleop::master::apply_controller_flags(f, p); });
  }
  return status;
}

/// The text of docs/configuration.md between the controller-parameters markers.
std::string docs_table() {
  std::ifstream in(std::string(TELEOP_SOURCE_DIR) + "/docs/configuration.md");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string doc = ss.str();
  const std::string open = "<!-- controller-parameters -->\n";
  const std::string close = "<!-- /controller-parameters -->";
  const auto a = doc.find(open);
  const auto b = doc.find(close);
  if (a == std::string::npos || b == std::string::npos || b < a) return "";
  return doc.substr(a + open.size(), b - a - open.size());
}

/// The cells of a markdown row, trimmed.
std::vector<std::string> cells_of(const std::string& row) {
  std::vector<std::string> cells;
  std::stringstream ss(row.substr(1));
  std::string cell;
  while (std::getline(ss, cell, '|')) {
    const auto first = cell.find_first_not_of(' ');
    const auto last = cell.find_last_not_of(' ');
    cells.push_back(first == std::string::npos ? "" : cell.substr(first, last - first + 1));
  }
  return cells;
}

const ControllerParam& entry(const std::string& key) {
  for (const ControllerParam& d : controller_param_table()) {
    if (d.key == key) return d;
  }
  throw std::runtime_error("no table entry " + key);
}

TEST(ControllerParams, TheTableIsConsistent) {
  std::set<std::string> keys, flags;
  const ControllerParams defaults;
  for (const ControllerParam& d : controller_param_table()) {
    EXPECT_TRUE(keys.insert(d.key).second) << d.key;
    if (!d.flag.empty()) {
      EXPECT_TRUE(flags.insert(d.flag).second) << d.flag;
    }
    EXPECT_FALSE(d.help.empty()) << d.key;
    if (d.kind() == ParamKind::kNumber || d.kind() == ParamKind::kPoint) {
      EXPECT_LT(d.lo, d.hi) << d.key;
      EXPECT_FALSE(d.unit.empty()) << d.key;
    }
    if (d.kind() == ParamKind::kChoice) {
      EXPECT_FALSE(d.choices.empty()) << d.key;
    }
    if (d.kind() == ParamKind::kBool && !d.flag.empty()) {
      EXPECT_FALSE(d.switch_help.empty()) << d.key;
    }
  }
  EXPECT_EQ(keys.size(), 19u);  // 16 and the workspace's 3
  // the flags teleop_master has always had
  EXPECT_EQ(flags, (std::set<std::string>{"--scheme", "--kps", "--kpm", "--bm", "--force-gain",
                                          "--position-scale", "--force-scale", "--max-force",
                                          "--wave-impedance", "--wave-unmatched", "--tdpa-base"}));
  EXPECT_NO_THROW(defaults.validate());
}

TEST(ControllerParams, EveryNumberRangeIsEnforcedByTheYamlLoader) {
  for (const ControllerParam& d : controller_param_table()) {
    if (d.kind() != ParamKind::kNumber) continue;
    EXPECT_EQ(entry(d.key).number(load(d.key, exact(d.lo))), d.lo) << d.key;
    EXPECT_EQ(entry(d.key).number(load(d.key, exact(d.hi))), d.hi) << d.key;
    for (const double bad : {below(d.lo), above(d.hi)}) {
      const std::string m = yaml_error(d.key, exact(bad));
      EXPECT_NE(m.find("ctl.yaml"), std::string::npos) << m;
      EXPECT_NE(m.find("'controller." + d.key + "'"), std::string::npos) << m;
      EXPECT_NE(m.find(range_text(d.lo, d.hi)), std::string::npos) << m;
    }
  }
}

TEST(ControllerParams, EveryNumberRangeIsEnforcedByValidate) {
  for (const ControllerParam& d : controller_param_table()) {
    if (d.kind() != ParamKind::kNumber) continue;
    for (const double v : {d.lo, d.hi}) {
      ControllerParams p;
      d.set_number(p, v);  // a field set by code, as a campaign does
      EXPECT_EQ(config_error_of([&] { p.validate(); }), "") << d.key;
    }
    for (const double v : {below(d.lo), above(d.hi)}) {
      ControllerParams p;
      d.set_number(p, v);
      const std::string m = config_error_of([&] { p.validate(); });
      EXPECT_EQ(m.rfind("controller: " + d.key + " = ", 0), 0u) << m;
      EXPECT_NE(m.find("is out of the allowed range " + range_text(d.lo, d.hi)), std::string::npos)
          << m;
    }
  }
}

TEST(ControllerParams, ValidateNamesTheFieldValueAndRange) {
  ControllerParams p;
  p.master_damping_ns_per_m = -1;
  EXPECT_EQ(config_error_of([&] { p.validate(); }),
            "controller: master_damping_ns_per_m = -1 is out of the allowed range [0, 10000]");
  p = ControllerParams{};
  p.workspace.force_scale = 2e3;
  EXPECT_EQ(config_error_of([&] { p.validate(); }),
            "controller: workspace.force_scale = 2000 is out of the allowed range [0.001, 1000]");
  p = ControllerParams{};
  p.scheme = "wave";
  EXPECT_EQ(config_error_of([&] { p.validate(); }),
            "controller: scheme 'wave' is unknown (allowed: position-position, force-position, "
            "wave-variables, tdpa, model-mediated)");
  p = ControllerParams{};
  p.tdpa_base = "tdpa";
  EXPECT_EQ(config_error_of([&] { p.validate(); }),
            "controller: tdpa_base 'tdpa' is unknown (allowed: position-position, force-position)");
  p = ControllerParams{};
  p.workspace.offset_m.y() = std::nan("");
  const std::string m = config_error_of([&] { p.validate(); });
  EXPECT_NE(m.find("controller: workspace.offset_m[1] = nan is out of the allowed range "
                   "[-1000, 1000]"),
            std::string::npos)
      << m;
}

TEST(ControllerParams, TheWorkspaceOffsetIsThreeNumbersEachInRange) {
  const ControllerParam& d = entry("workspace.offset_m");
  EXPECT_EQ(load(d.key, "[-1000, 0, 1000]").workspace.offset_m, Eigen::Vector3d(-1e3, 0.0, 1e3));
  const std::vector<std::string> bad_points = {"[0, 0, " + exact(above(d.hi)) + "]",
                                               "[" + exact(below(d.lo)) + ", 0, 0]", "[0, 0]",
                                               "[0, 0, 0, 0]"};
  for (const std::string& bad : bad_points) {
    const std::string m = yaml_error(d.key, bad);
    EXPECT_NE(m.find("'controller.workspace.offset_m'"), std::string::npos) << m;
    EXPECT_NE(m.find(range_text(d.lo, d.hi)), std::string::npos) << m;
  }
}

TEST(ControllerParams, BooleansAndChoicesTakeTheirValuesOnly) {
  for (const ControllerParam& d : controller_param_table()) {
    if (d.kind() == ParamKind::kBool) {
      const ControllerParam& e = entry(d.key);
      EXPECT_EQ(e.text(load(d.key, "false")), "false") << d.key;
      EXPECT_EQ(e.text(load(d.key, "true")), "true") << d.key;
      const std::string m = yaml_error(d.key, "maybe");
      EXPECT_NE(m.find("'controller." + d.key + "'"), std::string::npos) << m;
      EXPECT_NE(m.find("not a boolean"), std::string::npos) << m;
    }
    if (d.kind() == ParamKind::kChoice) {
      for (const std::string& c : d.choices) EXPECT_EQ(d.text(load(d.key, c)), c) << d.key;
      const std::string m = yaml_error(d.key, "bogus");
      EXPECT_NE(m.find("'controller." + d.key + "'"), std::string::npos) << m;
      EXPECT_NE(m.find(d.allowed_text()), std::string::npos) << m;
    }
  }
}

TEST(ControllerParams, EveryKeyIsAcceptedAndAnUnknownOneIsRefusedWithTheList) {
  // every key at once, each at its default: the loader takes them and changes nothing
  const ControllerParams defaults;
  std::string top, workspace;
  std::set<std::string> names;
  for (const ControllerParam& d : controller_param_table()) {
    const auto dot = d.key.find('.');
    std::string& into = dot == std::string::npos ? top : workspace;
    into += (into.empty() ? "" : ", ") + d.key.substr(dot == std::string::npos ? 0 : dot + 1) +
            ": " + d.text(defaults);
    names.insert(d.key.substr(0, dot));
  }
  const ControllerParams all = teleop::master::controller_params_from_yaml(
      Node::parse("{" + top + ", workspace: {" + workspace + "}}"));
  for (const ControllerParam& d : controller_param_table()) {
    EXPECT_EQ(d.text(all), d.text(defaults)) << d.key;
  }
  std::string m = yaml_error("bogus_gain", "1");
  EXPECT_NE(m.find("'controller.bogus_gain': unknown field"), std::string::npos) << m;
  for (const std::string& n : names) EXPECT_NE(m.find(n), std::string::npos) << n << ": " << m;
  m = yaml_error("workspace.rotation", "1");
  EXPECT_NE(m.find("'controller.workspace.rotation': unknown field; known fields here are "
                   "{force_scale, offset_m, position_scale}"),
            std::string::npos)
      << m;
}

TEST(ControllerParams, EveryNumberFlagEnforcesItsRange) {
  for (const ControllerParam& d : controller_param_table()) {
    if (d.flag.empty() || d.kind() != ParamKind::kNumber) continue;
    std::string err;
    for (const double v : {d.lo, d.hi}) {
      ControllerParams p;
      EXPECT_EQ(parse_flags({d.flag, exact(v)}, p, err), -1) << d.flag << ": " << err;
      EXPECT_EQ(err, "") << d.flag;
      EXPECT_EQ(d.number(p), v) << d.flag;
    }
    for (const double v : {below(d.lo), above(d.hi)}) {
      ControllerParams p;
      EXPECT_EQ(parse_flags({d.flag, exact(v)}, p, err), 2) << d.flag;
      EXPECT_NE(err.find(d.flag + ": '" + exact(v) + "'"), std::string::npos) << err;
      EXPECT_NE(err.find(range_text(d.lo, d.hi)), std::string::npos) << err;
    }
  }
}

TEST(ControllerParams, ChoiceFlagsAndSwitchesSetTheirFields) {
  std::string err;
  for (const ControllerParam& d : controller_param_table()) {
    if (d.flag.empty()) continue;
    ControllerParams p;
    if (d.kind() == ParamKind::kBool) {
      EXPECT_EQ(parse_flags({d.flag}, p, err), -1) << d.flag << ": " << err;
      EXPECT_EQ(d.text(p), d.switch_sets ? "true" : "false") << d.flag;
    }
    if (d.kind() != ParamKind::kChoice) continue;
    for (const std::string& c : d.choices) {
      EXPECT_EQ(parse_flags({d.flag, c}, p, err), -1) << d.flag << ": " << err;
      EXPECT_EQ(d.text(p), c);
    }
    EXPECT_EQ(parse_flags({d.flag, "bogus"}, p, err), 2) << d.flag;
    EXPECT_NE(err.find(d.flag), std::string::npos) << err;
  }
}

TEST(ControllerParams, FlagsApplyOnTopOfTheConfigFile) {
  ControllerParams p = teleop::master::controller_params_from_yaml(
      Node::parse("{scheme: tdpa, slave_stiffness_n_per_m: 900, force_gain: 0.5}"));
  std::string err;
  EXPECT_EQ(parse_flags({"--kps", "1200", "--wave-unmatched"}, p, err), -1) << err;
  EXPECT_EQ(p.scheme, "tdpa");
  EXPECT_EQ(p.slave_stiffness_n_per_m, 1200.0);
  EXPECT_EQ(p.force_gain, 0.5);
  EXPECT_FALSE(p.wave_matched);
  EXPECT_EQ(parse_flags({"--scheme", "wave-variables"}, p, err), -1) << err;
  EXPECT_EQ(p.scheme, "wave-variables");
}

TEST(ControllerParams, TheHelpListsEachFlagWithUnitRangeAndDefault) {
  CLI::App app{"prog"};
  ControllerFlags f;
  teleop::master::add_controller_flags(app, f);
  const std::string help = app.help();
  const ControllerParams defaults;
  for (const ControllerParam& d : controller_param_table()) {
    if (d.flag.empty()) continue;
    EXPECT_NE(help.find(d.flag), std::string::npos) << d.flag;
    EXPECT_NE(help.find(d.flag_help()), std::string::npos) << d.flag;
    if (d.kind() == ParamKind::kNumber) {
      EXPECT_NE(d.flag_help().find("[" + d.unit + "], " + d.allowed_text()), std::string::npos);
    }
  }
  EXPECT_NE(help.find("}=force-position"), std::string::npos) << help;  // the default
  EXPECT_NE(help.find("NUMBER in [0, 1e6]"), std::string::npos) << help;
}

TEST(ControllerParams, TheDocsTableIsTheTable) {
  EXPECT_EQ(docs_table(), teleop::master::controller_params_markdown())
      << "docs/configuration.md's controller table differs from `teleop_master "
         "--print-parameters`; paste its output between the controller-parameters markers";
}

TEST(ControllerParams, DefaultsInTheDocsAreTheStructs) {
  const ControllerParams defaults;
  std::stringstream rows(docs_table());
  std::string row;
  std::set<std::string> seen;
  while (std::getline(rows, row)) {
    const std::vector<std::string> c = cells_of(row);
    ASSERT_GE(c.size(), 6u) << row;
    if (c[0] == "key" || c[0].rfind("---", 0) == 0) continue;
    const std::string key = c[0].substr(1, c[0].size() - 2);  // `key`
    const ControllerParam& d = entry(key);
    seen.insert(key);
    if (d.kind() == ParamKind::kNumber) {
      EXPECT_EQ(std::stod(c[3]), d.number(defaults)) << key;  // the value, not only its text
    } else {
      EXPECT_EQ(c[3], d.text(defaults)) << key;
    }
  }
  EXPECT_EQ(seen.size(), controller_param_table().size());
}

TEST(ControllerParams, EachSchemesParametersAreListedUnderThatScheme) {
  const std::map<std::string, std::vector<std::string>> own = {
      {"position-position", {}},
      {"force-position", {}},
      {"wave-variables",
       {"wave_impedance_ns_per_m", "wave_time_constant_s", "wave_matched", "wave_filter_hz"}},
      {"tdpa", {"tdpa_base"}},
      {"model-mediated", {"mmt_blend_s", "mmt_energy_rate_w", "mmt_energy_burst_j"}},
  };
  std::size_t scheme_owned = 0;
  for (const std::string& name : teleop::master::controller_names()) {
    std::vector<std::string> keys;
    for (const ControllerParam& d : teleop::master::scheme_params(name)) keys.push_back(d.key);
    EXPECT_EQ(keys, own.at(name)) << name;
    scheme_owned += keys.size();
  }
  std::size_t common = 0;
  for (const ControllerParam& d : controller_param_table()) {
    if (d.scheme.empty()) ++common;
    // the docs' help and the flag's say whose it is
    if (!d.scheme.empty()) {
      EXPECT_EQ(d.flag_help().rfind(d.scheme + ": ", 0), 0u) << d.key;
    }
  }
  EXPECT_EQ(common, teleop::master::common_controller_params().size());
  EXPECT_EQ(common + scheme_owned, controller_param_table().size());
  const std::string m = config_error_of([] { teleop::master::scheme_params("wave"); });
  EXPECT_NE(m.find("scheme 'wave' is unknown (allowed: position-position"), std::string::npos) << m;
}

TEST(ControllerParams, NumbersAreWrittenShort) {
  using teleop::master::param_number_text;
  EXPECT_EQ(param_number_text(1e6), "1e6");
  EXPECT_EQ(param_number_text(1e4), "10000");
  EXPECT_EQ(param_number_text(1e-4), "0.0001");
  EXPECT_EQ(param_number_text(1e-5), "1e-5");
  EXPECT_EQ(param_number_text(2e-4), "0.0002");
  EXPECT_EQ(param_number_text(-1e3), "-1000");
  EXPECT_EQ(param_number_text(0.025), "0.025");
  EXPECT_EQ(param_number_text(0.0), "0");
}

}  // namespace
