// The shared command-line rules (common/config/flags.hpp, config.hpp: parse_number & co).
#include "common/config/flags.hpp"

#include "common/util/files.hpp"
#include "common/util/version.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace {

using teleop::config::ConfigError;
using teleop::config::number_problem;

TEST(NumberProblem, AcceptsWholeFiniteNumbersInRange) {
  EXPECT_EQ(number_problem("0", 0.0, 1.0, false), "");
  EXPECT_EQ(number_problem("0.5", 0.0, 1.0, false), "");
  EXPECT_EQ(number_problem("1e-3", 0.0, 1.0, false), "");
  EXPECT_EQ(number_problem("-1", -1.0, 1.0, false), "");
  EXPECT_EQ(number_problem("-0", -1.0, 1.0, false), "");  // a range below 0: -0 is 0
  EXPECT_EQ(number_problem("232", 0.0, 232.0, true), "");
}

TEST(NumberProblem, RefusesEmptyPartialNegativeZeroAndNonFinite) {
  for (const char* bad : {"", " 1", "1 ", "3x", "0x10", "nan", "inf", "-inf", "1e999", "-0", "-0.0",
                          "-1", "2", "--1", "1,2"}) {
    const std::string p = number_problem(bad, 0.0, 1.0, false);
    EXPECT_FALSE(p.empty()) << "'" << bad << "' accepted";
    EXPECT_NE(p.find(std::string("'") + bad + "'"), std::string::npos) << p;  // names the value
    EXPECT_NE(p.find("[0, 1]"), std::string::npos) << p;                      // and the range
  }
}

TEST(NumberProblem, IntegersRefuseFractions) {
  EXPECT_FALSE(number_problem("1.5", 0.0, 10.0, true).empty());
  EXPECT_FALSE(number_problem("1e3", 0.0, 1e4, true).empty());
  EXPECT_FALSE(number_problem("1.0", 0.0, 10.0, true).empty());
  EXPECT_EQ(teleop::config::parse_integer("--n", "7", 0, 10), 7);
}

TEST(CheckFlag, RefusesNegativeZeroWhereTheRangeStartsAtZero) {
  EXPECT_THROW(teleop::config::check_flag("--duration", -0.0, 0.0, 10.0), ConfigError);
  EXPECT_EQ(teleop::config::check_flag("--cpu", -0.0, -1.0, 10.0), 0.0);
  EXPECT_THROW(teleop::config::check_flag("--x", std::nan(""), 0.0, 10.0), ConfigError);
}

TEST(ParseNumbers, NeedsExactlyTheCountInRange) {
  const std::vector<double> lo(3, -100.0), hi(3, 100.0);
  const auto v = teleop::config::parse_numbers("--contact-point", "1,-2,3.5", 3, lo, hi);
  ASSERT_EQ(v.size(), 3u);
  EXPECT_DOUBLE_EQ(v[1], -2.0);
  for (const char* bad : {"1,2,3,4", "1,2", "", "1,,3", "1,2,3,", "1,2,x", "1000,0,0", "1;2;3"}) {
    try {
      teleop::config::parse_numbers("--contact-point", bad, 3, lo, hi);
      ADD_FAILURE() << "'" << bad << "' accepted";
    } catch (const ConfigError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("--contact-point"), std::string::npos) << what;
      EXPECT_NE(what.find("[-100, 100]"), std::string::npos) << what;
    }
  }
}

/// Runs a CLI11 app with the shared rules on `args`; returns the exit status (-1: go on).
int parse(CLI::App& app, std::vector<std::string> args) {
  args.insert(args.begin(), "prog");
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  return teleop::config::parse_command_line(app, "prog", static_cast<int>(argv.size()),
                                            argv.data());
}

struct App {
  CLI::App app{"test"};
  double duration = 0.0;
  std::optional<std::string> out;
  std::vector<std::string> exclude;
  bool quiet = false;
  App() {
    app.add_option("--duration", duration)->check(teleop::config::number_in(0.0, 10.0));
    app.add_option("--out", out);
    app.add_option("--exclude", exclude);
    app.add_flag("--quiet", quiet);
  }
};

/// A fresh App parsed with `args`.
int run(const std::vector<std::string>& args) {
  App a;
  return parse(a.app, args);
}

TEST(HardenFlags, RefusesEmptyRepeatedUnknownAndOutOfRange) {
  EXPECT_EQ(run({"--duration", "1", "--out", "x", "--exclude", "a", "--exclude", "b", "--quiet",
                 "--quiet"}),
            -1);
  EXPECT_EQ(run({"--duration", ""}), 2);
  EXPECT_EQ(run({"--duration=-0"}), 2);
  EXPECT_EQ(run({"--duration", "11"}), 2);
  EXPECT_EQ(run({"--out", ""}), 2);
  EXPECT_EQ(run({"--out="}), 2);
  EXPECT_EQ(run({"--out", "a", "--out", "b"}), 2);
  EXPECT_EQ(run({"--exclude", ""}), 2);
  EXPECT_EQ(run({"--bogus"}), 2);
  EXPECT_EQ(run({"stray"}), 2);
}

/// Flags declared with add_number / add_integer, as the programs declare theirs.
struct RangedApp {
  CLI::App app{"test"};
  double duration_s = 0.0;
  double rate_hz = 1000.0;
  std::optional<double> period_s;
  int nice = 19;
  std::uint64_t samples = 0;
  std::optional<int> domain;
  RangedApp() {
    using teleop::config::add_integer;
    using teleop::config::add_number;
    add_number(app, "--duration", duration_s, 0.0, 1e6, "session length (0 = no limit)", "s");
    add_number(app, "--rate", rate_hz, 10.0, 20000.0, "loop rate", "Hz")->capture_default_str();
    add_number(app, "--period", period_s, 0.05, 60.0, "print period", "s");
    add_integer(app, "--nice", nice, 0, 19, "niceness")->capture_default_str();
    add_integer(app, "--samples", samples, 0, 1e12, "stop after N cycles");
    add_integer(app, "--domain", domain, 0, 232, "DDS domain id");
  }
};

/// CLI11's refusal of `args` by a fresh RangedApp ("" when it accepts them).
std::string ranged_refusal(std::vector<std::string> args) {
  RangedApp a;
  teleop::config::harden_flags(a.app);
  std::reverse(args.begin(), args.end());  // CLI11 takes the arguments last first
  try {
    a.app.parse(args);
  } catch (const CLI::ParseError& e) {
    return e.what();
  }
  return "";
}

TEST(AddNumber, TheHelpGivesTheUnitAndTheRangeOnce) {
  RangedApp a;
  const std::string help = a.app.help();
  EXPECT_NE(help.find("session length (0 = no limit) [s], [0, 1e6]"), std::string::npos) << help;
  EXPECT_NE(help.find("loop rate [Hz], [10, 20000]"), std::string::npos) << help;
  EXPECT_NE(help.find("niceness, [0, 19]"), std::string::npos) << help;  // no unit: no brackets
  EXPECT_NE(help.find("stop after N cycles, [0, 1e12]"), std::string::npos) << help;
  EXPECT_NE(help.find("=1000"), std::string::npos) << help;  // the default, where captured
  EXPECT_EQ(a.app.get_option("--duration")->get_description(),
            "session length (0 = no limit) [s], [0, 1e6]");
  EXPECT_EQ(teleop::config::number_help("gain", "N/m", 0.0, 1e-5), "gain [N/m], [0, 1e-5]");
}

TEST(AddNumber, OutOfRangeEmptyAndNegativeZeroAreRefusedNamingFlagValueAndRange) {
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  const Case cases[] = {
      {{"--rate", "5"}, "--rate: '5' is out of the allowed range [10, 20000]"},
      {{"--rate", "20001"}, "--rate: '20001' is out of the allowed range [10, 20000]"},
      {{"--rate", ""}, "--rate: '' is empty, not a number (allowed range [10, 20000])"},
      {{"--rate", "3x"},
       "--rate: '3x' is not a number (it ends in 'x') (allowed range [10, 20000])"},
      {{"--period", "-0"}, "--period: '-0' is out of the allowed range [0.05, 60]"},
      {{"--duration", "-0"}, "--duration: '-0' is negative; the allowed range is [0, 1e6]"},
      {{"--duration", "nan"}, "--duration: 'nan' is not a finite number"},
      {{"--nice", "20"}, "--nice: '20' is out of the allowed range [0, 19]"},
      {{"--nice", "-0"}, "--nice: '-0' is negative; the allowed range is [0, 19]"},
      {{"--nice", "1.5"}, "--nice: '1.5' is not a whole number (allowed range [0, 19])"},
      {{"--domain", ""}, "--domain: '' is empty, not a number (allowed range [0, 232])"},
      {{"--samples", "-1"}, "--samples: '-1' is out of the allowed range [0, 1e12]"},
  };
  for (const Case& c : cases) {
    const std::string m = ranged_refusal(c.args);
    EXPECT_NE(m.find(c.message), std::string::npos)
        << "expected '" << c.message << "', got '" << m << "'";
  }
}

TEST(AddNumber, AValueInRangeIsSet) {
  RangedApp a;
  std::vector<std::string> args = {"--duration", "2.5",           "--rate",   "10",
                                   "--period",   "0.05",          "--nice",   "0",
                                   "--samples",  "1000000000000", "--domain", "7"};
  std::reverse(args.begin(), args.end());
  ASSERT_NO_THROW(a.app.parse(args));
  EXPECT_DOUBLE_EQ(a.duration_s, 2.5);
  EXPECT_DOUBLE_EQ(a.rate_hz, 10.0);
  ASSERT_TRUE(a.period_s.has_value());
  EXPECT_DOUBLE_EQ(*a.period_s, 0.05);
  EXPECT_EQ(a.nice, 0);
  EXPECT_EQ(a.samples, 1000000000000u);
  EXPECT_EQ(a.domain, std::optional<int>(7));
  RangedApp untouched;  // a flag not given keeps its default, an optional one stays unset
  ASSERT_NO_THROW(untouched.app.parse(std::vector<std::string>{}));
  EXPECT_DOUBLE_EQ(untouched.rate_hz, 1000.0);
  EXPECT_FALSE(untouched.period_s.has_value());
  EXPECT_FALSE(untouched.domain.has_value());
}

TEST(DidYouMean, NamesTheClosestKnownFlag) {
  using teleop::config::closest_name;
  const std::vector<std::string> names = {"--level", "--duration", "--out", "--quick"};
  EXPECT_EQ(closest_name("--levle", names), "--level");       // two letters swapped
  EXPECT_EQ(closest_name("--duraton", names), "--duration");  // one left out
  EXPECT_EQ(closest_name("--ot", names), "--out");
  EXPECT_EQ(closest_name("--bogus", names), "");  // nothing close
  EXPECT_EQ(closest_name("", names), "");
  EXPECT_EQ(teleop::config::did_you_mean("--levle", names), " (did you mean '--level'?)");
  EXPECT_EQ(teleop::config::did_you_mean("--zzzzzz", names), "");
}

TEST(HardenFlags, AnUnknownFlagIsRefusedWithTheClosestOne) {
  testing::internal::CaptureStderr();
  EXPECT_EQ(run({"--duraton", "1"}), 2);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("'--duraton' is not an option of prog (did you mean '--duration'?)"),
            std::string::npos)
      << err;
  EXPECT_EQ(err.find("'1' is not expected"), std::string::npos) << err;  // its value, not listed
  testing::internal::CaptureStderr();
  EXPECT_EQ(run({"stray"}), 2);
  EXPECT_NE(testing::internal::GetCapturedStderr().find("'stray' is not expected"),
            std::string::npos);
}

TEST(HardenFlags, VersionAndHelpRunNothing) {
  testing::internal::CaptureStdout();
  EXPECT_EQ(run({"--version"}), 0);
  const std::string out = testing::internal::GetCapturedStdout();
  EXPECT_NE(out.find("prog " + std::string(teleop::project_version()) + " (git "),
            std::string::npos)
      << out;
  testing::internal::CaptureStdout();
  EXPECT_EQ(run({"--help", "--duration", "1"}), 0);
  testing::internal::GetCapturedStdout();
}

TEST(PrepareOutput, MakesMissingFoldersAndRefusesImpossibleOnes) {
  char dir[] = "/tmp/flags_out_XXXXXX";
  ASSERT_NE(mkdtemp(dir), nullptr);
  const std::string root = dir;
  // a missing folder is made, with its parents
  EXPECT_NO_THROW(teleop::prepare_output_file("--summary-json", root + "/a/b/s.json"));
  struct stat st {};
  EXPECT_EQ(stat((root + "/a/b").c_str(), &st), 0);
  EXPECT_NO_THROW(teleop::prepare_output_dir("--out", root + "/c/d"));
  EXPECT_EQ(stat((root + "/c/d").c_str(), &st), 0);
  EXPECT_NO_THROW(teleop::prepare_output_file("--log", "log.csv"));  // the working folder
  // an existing file is replaced in place, whatever its folder allows (a write error on a full
  // device comes later, naming the file)
  EXPECT_NO_THROW(teleop::prepare_output_file("--log", "/dev/full"));
  // a folder under a file, a file where a folder is wanted, a folder as the file: refused
  const std::string file = root + "/file";
  std::FILE* f = std::fopen(file.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fclose(f);
  auto refused = [](const std::function<void()>& call, const std::string& names) {
    try {
      call();
      ADD_FAILURE() << names << " accepted";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(names), std::string::npos) << e.what();
    }
  };
  refused([&] { teleop::prepare_output_file("--log", file + "/x.csv"); }, "--log '" + file);
  refused([&] { teleop::prepare_output_dir("--out", file); }, "is not a folder");
  refused([&] { teleop::prepare_output_file("--summary-json", root); }, "is a folder");
  std::filesystem::remove_all(root);
}

TEST(RequireRegularFile, RefusesFifosDevicesAndDirectories) {
  char dir[] = "/tmp/flags_test_XXXXXX";
  ASSERT_NE(mkdtemp(dir), nullptr);
  const std::string fifo = std::string(dir) + "/fifo", file = std::string(dir) + "/f.yaml";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  std::FILE* f = std::fopen(file.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fclose(f);
  EXPECT_NO_THROW(teleop::config::require_regular_file(file, "scene"));
  EXPECT_NO_THROW(teleop::config::require_regular_file("/dev/null", "scene"));
  for (const std::string& bad : {fifo, std::string("/dev/zero"), std::string(dir),
                                 std::string(dir) + "/missing", std::string()}) {
    try {
      teleop::config::require_regular_file(bad, "scene");
      ADD_FAILURE() << bad << " accepted";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
  std::remove(fifo.c_str());
  std::remove(file.c_str());
  rmdir(dir);
}

}  // namespace
