// The injected channel's parameter table: each parameter declared once, and the flag parser,
// the YAML loader, validate() and teleop_master's flags all reading the same entry.
#include "client/net/delay_params.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <string>
#include <vector>

#include "client/net/delay_flags.hpp"
#include "common/config/flags.hpp"
#include "tests/support/config_error.hpp"

namespace {

using teleop::config::Node;
using teleop::master::delay_param;
using teleop::master::delay_param_table;
using teleop::master::DelayConfig;
using teleop::master::DelayParam;
using teleop::master::DelayParamKind;
using teleop::master::DelayQuantity;

using teleop::test::config_error_of;

DelayConfig from_yaml(const std::string& mapping) {
  return teleop::master::delay_config_from_yaml(Node::parse("d: " + mapping, "net.yaml").at("d"));
}

/// A flag's text for a value of each number of `d` (durations in ms, probabilities in %).
std::string flag_text(const DelayParam& d, const std::vector<double>& v) {
  std::string s;
  for (std::size_t i = 0; i < v.size(); ++i) {
    const bool duration = d.parts[i].quantity == DelayQuantity::kDuration;
    s += (i ? "," : "") + std::to_string(duration ? v[i] * 1e3 : v[i] * 1e2) +
         (duration ? "ms" : "%");
  }
  return s;
}

/// The same values as a YAML value (plain numbers: seconds and fractions).
std::string yaml_text(const std::vector<double>& v) {
  std::string s;
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + std::to_string(v[i]);
  return v.size() == 1 ? s : "[" + s + "]";
}

TEST(DelayParams, EachKeyAndFlagIsDeclaredOnceAndEveryFieldHasAnEntry) {
  std::set<std::string> keys, flags;
  std::set<const void*> fields;
  for (const DelayParam& d : delay_param_table()) {
    EXPECT_TRUE(keys.insert(d.key).second) << d.key;
    EXPECT_TRUE(flags.insert(d.flag).second) << d.flag;
    EXPECT_FALSE(d.help.empty()) << d.key;
    for (const auto& p : d.parts) EXPECT_LT(p.lo, p.hi) << d.key << " " << p.name;
    if (d.kind == DelayParamKind::kCount) {
      EXPECT_LT(d.lo, d.hi) << d.key;
    }
  }
  // every field of DelayConfig a user sets is some entry's: the 10 entries set 16 fields
  std::size_t set_fields = 0;
  for (const DelayParam& d : delay_param_table()) {
    set_fields += d.kind == DelayParamKind::kNumbers ? d.parts.size() : 1;
    if (d.kind == DelayParamKind::kNumbers && d.enable != nullptr) ++set_fields;
  }
  EXPECT_EQ(delay_param_table().size(), 10u);
  EXPECT_EQ(set_fields, 16u);
}

TEST(DelayParams, AFlagAndAFileGiveTheSameChannel) {
  for (const DelayParam& d : delay_param_table()) {
    if (d.kind != DelayParamKind::kNumbers) continue;
    std::vector<double> v;
    for (const auto& p : d.parts) v.push_back(p.lo + 0.25 * (std::min(p.hi, 1.0) - p.lo));
    DelayConfig by_flag;
    d.apply_flag(flag_text(d, v), by_flag);
    const DelayConfig by_file = from_yaml("{" + d.key + ": " + yaml_text(v) + "}");
    for (std::size_t i = 0; i < v.size(); ++i) {
      EXPECT_NEAR(by_flag.*(d.parts[i].field), v[i], 1e-12) << d.flag;
      EXPECT_EQ(by_flag.*(d.parts[i].field), by_file.*(d.parts[i].field)) << d.key;
    }
    if (d.enable != nullptr) {
      EXPECT_TRUE(by_flag.*(d.enable) && by_file.*(d.enable)) << d.key;
    }
  }
  DelayConfig c;
  delay_param("jitter_dist").apply_flag("normal", c);
  delay_param("reorder").apply_flag("", c);
  delay_param("seed").apply_flag("9007199254740992", c);
  delay_param("capacity").apply_flag("16777216", c);
  const DelayConfig y =
      from_yaml("{jitter_dist: normal, reorder: true, seed: 9007199254740992, capacity: 16777216}");
  EXPECT_EQ(c.jitter_dist, y.jitter_dist);
  EXPECT_EQ(c.reorder, y.reorder);
  EXPECT_EQ(c.seed, y.seed);
  EXPECT_EQ(c.seed, 9007199254740992u);
  EXPECT_EQ(c.capacity, y.capacity);
}

TEST(DelayParams, AValuePastItsRangeIsRefusedByTheFlagTheFileAndValidateAlike) {
  for (const DelayParam& d : delay_param_table()) {
    if (d.kind != DelayParamKind::kNumbers) continue;
    for (std::size_t i = 0; i < d.parts.size(); ++i) {
      std::vector<double> v;
      for (const auto& p : d.parts) v.push_back(p.hi);
      v[i] = d.parts[i].hi * 1.5;
      if (d.parts[i].quantity == DelayQuantity::kProbability) v[i] = 1.5;
      const std::string flag = config_error_of([&] {
        DelayConfig c;
        d.apply_flag(flag_text(d, v), c);
      });
      EXPECT_NE(flag.find("command line: " + d.flag), std::string::npos) << flag;
      const std::string file =
          config_error_of([&] { from_yaml("{" + d.key + ": " + yaml_text(v) + "}"); });
      EXPECT_NE(file.find("net.yaml: field 'd." + d.key + "'"), std::string::npos) << file;
      DelayConfig c;
      if (d.enable != nullptr) c.*(d.enable) = true;
      c.*(d.parts[i].field) = v[i];
      const std::string checked = config_error_of([&] { c.validate(); });
      EXPECT_NE(checked.find("delay channel: " + d.key), std::string::npos) << checked;
      // each names the allowed range of the part that is out (probabilities: also in %)
      const std::string range = d.parts[i].quantity == DelayQuantity::kProbability
                                    ? "0, 1]"
                                    : "[0, " + teleop::config::param_number_text(d.parts[i].hi);
      for (const std::string* m : {&flag, &file, &checked}) {
        EXPECT_NE(m->find(range), std::string::npos) << *m;
      }
    }
  }
  EXPECT_NE(config_error_of([] { from_yaml("{seed: 9007199254740994}"); }).find("2^53"),
            std::string::npos);
  EXPECT_NE(config_error_of([] {
              DelayConfig c;
              delay_param("capacity").apply_flag("1", c);
            }).find("[2, 16777216]"),
            std::string::npos);
  EXPECT_NE(config_error_of([] { from_yaml("{burst_loss: [0.1, 0]}"); }).find("never end"),
            std::string::npos);
}

TEST(DelayParams, AFileTakesTheScheduledFaultsAndRefusesTheWrongShape) {
  const DelayConfig c = from_yaml("{delay_spike: [3s, 1s, 200ms], loss_window: [4, 0.5, 50%]}");
  EXPECT_DOUBLE_EQ(c.spike_at_s, 3.0);
  EXPECT_DOUBLE_EQ(c.spike_duration_s, 1.0);
  EXPECT_DOUBLE_EQ(c.spike_extra_s, 0.2);
  EXPECT_DOUBLE_EQ(c.window_at_s, 4.0);
  EXPECT_DOUBLE_EQ(c.window_loss, 0.5);
  std::string m = config_error_of([] { from_yaml("{delay_spike: [3s, 1s]}"); });
  EXPECT_NE(m.find("'d.delay_spike'"), std::string::npos) << m;
  EXPECT_NE(m.find("list of 3"), std::string::npos) << m;
  m = config_error_of([] {
    DelayConfig d;
    delay_param("delay_spike").apply_flag("3s,1s", d);
  });
  EXPECT_NE(m.find("must be at,duration,extra (example: 3s,1s,1s)"), std::string::npos) << m;
  m = config_error_of([] { from_yaml("{capacity: 1.5}"); });
  EXPECT_NE(m.find("'d.capacity'"), std::string::npos) << m;
}

TEST(DelayParams, TheProgramsFlagsAreTheTablesAndApplyOverAFile) {
  CLI::App app;
  teleop::master::DelayFlags f;
  teleop::master::add_delay_flags(app, f, "both directions");
  for (const DelayParam& d : delay_param_table()) {
    const CLI::Option* o = app.get_option(d.flag);
    ASSERT_NE(o, nullptr) << d.flag;
    EXPECT_NE(o->get_description().find(d.help), std::string::npos) << d.flag;
    if (d.kind != DelayParamKind::kSwitch) {
      EXPECT_NE(o->get_description().find(d.allowed_text()), std::string::npos) << d.flag;
    }
  }
  std::vector<std::string> args = {"--seed", "7", "--delay", "20ms", "--reorder"};
  std::reverse(args.begin(), args.end());  // CLI11 parses a vector from its back
  app.parse(args);
  ASSERT_TRUE(f.any());
  DelayConfig c = from_yaml("{delay: 80ms, loss: 2%}");
  teleop::master::apply_delay_flags(f, c);
  EXPECT_DOUBLE_EQ(c.delay_s, 0.02);           // the flag wins
  EXPECT_DOUBLE_EQ(c.loss_probability, 0.02);  // the file's stays
  EXPECT_EQ(c.seed, 7u);
  EXPECT_TRUE(c.reorder);
}

TEST(DelayParams, TheDocsTableHasARowPerParameterWithItsDefault) {
  const std::string md = teleop::master::delay_params_markdown();
  const DelayConfig defaults;
  for (const DelayParam& d : delay_param_table()) {
    const std::string row = "| `" + d.key + "` | `" + d.flag + "` | " + d.unit_text() + " | " +
                            d.text(defaults) + " | " + d.allowed_text() + " | ";
    EXPECT_NE(md.find(row), std::string::npos) << row;
  }
  EXPECT_NE(md.find("| `capacity` | `--channel-capacity` |  | 4096 | [2, 16777216]"),
            std::string::npos)
      << md;
}

}  // namespace
