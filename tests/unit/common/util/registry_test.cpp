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

TEST(Registry, AnUnknownOptionNamesTheClosestOne) {
  try {
    teleop::parse_command_args(entry(), {"--out", "o", "--levle", "3"});
    ADD_FAILURE() << "--levle accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("'--levle' is not an option of demo (did you mean "
                                         "'--level'?)"),
              std::string::npos)
        << e.what();
  }
}

int demo_runs = 0;
int run_demo(const CommandArgs&) { return ++demo_runs, 0; }
TELEOP_REGISTER_COMMAND(registry_test, "demo", "a command that counts its runs", run_demo,
                        teleop::integer_option("--level", 0, 6, "level"));

/// run_registry_main of the test group on `words`, with stdout and stderr captured.
int main_of(std::vector<std::string> words, std::string* err = nullptr) {
  words.insert(words.begin(), "tool");
  std::vector<char*> argv;
  for (auto& w : words) argv.push_back(w.data());
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  const int status = teleop::run_registry_main("registry_test", "tool",
                                               static_cast<int>(argv.size()), argv.data());
  testing::internal::GetCapturedStdout();
  const std::string e = testing::internal::GetCapturedStderr();
  if (err) *err = e;
  return status;
}

TEST(RegistryMain, HelpListAndVersionRunNothing) {
  demo_runs = 0;
  EXPECT_EQ(main_of({"demo", "--help"}), 0);
  EXPECT_EQ(main_of({"demo", "--out", "/nonexistent/x", "--levle", "3", "--help"}), 0);
  EXPECT_EQ(main_of({"list"}), 0);
  EXPECT_EQ(main_of({"--version"}), 0);
  EXPECT_EQ(main_of({"--help"}), 0);
  EXPECT_EQ(demo_runs, 0);
}

TEST(RegistryMain, MistakesExit2BeforeTheCommandRuns) {
  demo_runs = 0;
  std::string err;
  EXPECT_EQ(main_of({"dmeo", "--out", "o"}, &err), 2);
  EXPECT_NE(err.find("unknown name 'dmeo' (did you mean 'demo'?)"), std::string::npos) << err;
  EXPECT_EQ(main_of({"demo", "--out", "/dev/null/x"}, &err), 2);  // a folder under a file
  EXPECT_NE(err.find("--out '/dev/null/x'"), std::string::npos) << err;
  EXPECT_EQ(main_of({"demo", "--out", "o", "--out", "p"}, &err), 2);
  EXPECT_EQ(demo_runs, 0);
}

TEST(NanAsNa, ReplacesOnlyWholeWords) {
  EXPECT_EQ(teleop::nan_as_na("p50 nan ms, -nan N, inf, -inf x"), "p50 n/a ms, n/a N, n/a, n/a x");
  EXPECT_EQ(teleop::nan_as_na("finance nano info 1.5"), "finance nano info 1.5");
  EXPECT_EQ(teleop::nan_as_na("nan"), "n/a");
}

}  // namespace

TEST(Registry, ProgressFlagsSetTheMode) {
  EXPECT_EQ(teleop::parse_command_args(entry(), {"--out", "o"}).progress,
            teleop::ProgressMode::kAuto);
  EXPECT_EQ(teleop::parse_command_args(entry(), {"--out", "o", "--progress"}).progress,
            teleop::ProgressMode::kOn);
  EXPECT_EQ(teleop::parse_command_args(entry(), {"--no-progress", "--out", "o"}).progress,
            teleop::ProgressMode::kOff);
  EXPECT_THROW(teleop::parse_command_args(entry(), {"--out", "o", "--progress=1"}), ConfigError);
}
