// The tools' shared command line (common/util/registry.hpp) and the text summaries' n/a.
#include "common/util/registry.hpp"

#include <gtest/gtest.h>

#include "common/config/config.hpp"
#include "common/util/json.hpp"

namespace {

using teleop::CommandArgs;
using teleop::CommandEntry;
using teleop::config::ConfigError;

CommandEntry entry() {
  CommandEntry e;
  e.name = "demo";
  e.options = {teleop::text_option("--scene", "scene"),
               teleop::number_option("--dt", 1e-6, 1e-2, "step"),
               teleop::integer_option("--level", 0, 6, "level")};
  return e;
}

TEST(Registry, ParsesDeclaredOptions) {
  const CommandArgs a = teleop::parse_command_args(
      entry(), {"--out", "o", "--quick", "--scene", "s.yaml", "--dt=0.001", "--level", "3"});
  EXPECT_EQ(a.out_dir, "o");
  EXPECT_TRUE(a.quick);
  EXPECT_EQ(a.option("--scene", ""), "s.yaml");
  EXPECT_EQ(a.option("--dt", ""), "0.001");
  EXPECT_EQ(a.option("--level", ""), "3");
}

TEST(Registry, RefusesUnknownRepeatedEmptyAndOutOfRange) {
  const std::vector<std::vector<std::string>> bad = {
      {"--scene", "s"},                // no --out
      {"--out", "o", "--out", "p"},    // repeated
      {"--out", ""},                   // empty
      {"--out", "o", "--bogus", "1"},  // unknown
      {"--out", "o", "stray"},         // a stray word
      {"--out", "o", "--scene", "a", "--scene", "b"},
      {"--out", "o", "--dt", "-0"},
      {"--out", "o", "--dt", "1"},
      {"--out", "o", "--dt", "0.001x"},
      {"--out", "o", "--level", "2.5"},
      {"--out", "o", "--level"},  // no value
      {"--out", "o", "--quick=1"},
  };
  for (const auto& words : bad) {
    EXPECT_THROW(teleop::parse_command_args(entry(), words), ConfigError) << words.back();
  }
}

TEST(NanAsNa, ReplacesOnlyWholeWords) {
  EXPECT_EQ(teleop::nan_as_na("p50 nan ms, -nan N, inf, -inf x"), "p50 n/a ms, n/a N, n/a, n/a x");
  EXPECT_EQ(teleop::nan_as_na("finance nano info 1.5"), "finance nano info 1.5");
  EXPECT_EQ(teleop::nan_as_na("nan"), "n/a");
}

}  // namespace
