#pragma once
// Named sub-commands for the tool executables (teleop_experiment, teleop_bench).
// A .cpp linked directly into the executable registers itself with
//   TELEOP_REGISTER_COMMAND(experiments, "sphere-zero-g", "experiment 1 ...", run_fn);
// where run_fn is `int (const teleop::CommandArgs&)`.
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "common/util/progress.hpp"

namespace teleop {

/// One option a command accepts: `--name VALUE`. The shared main refuses, before the command
/// runs, an option the command does not declare, one given twice, an empty value, and for a
/// number (or integer) option a value that is not wholly a finite number within [lo, hi].
struct OptionSpec {
  enum class Kind { kText, kNumber, kInteger };
  std::string name;  ///< "--scene"
  Kind kind = Kind::kText;
  double lo = 0.0;  ///< range of a number or integer option
  double hi = 0.0;
  std::string help;  ///< shown by `<exe> --help`
};
inline OptionSpec text_option(std::string name, std::string help) {
  return {std::move(name), OptionSpec::Kind::kText, 0.0, 0.0, std::move(help)};
}
inline OptionSpec number_option(std::string name, double lo, double hi, std::string help) {
  return {std::move(name), OptionSpec::Kind::kNumber, lo, hi, std::move(help)};
}
inline OptionSpec integer_option(std::string name, double lo, double hi, std::string help) {
  return {std::move(name), OptionSpec::Kind::kInteger, lo, hi, std::move(help)};
}

struct CommandArgs {
  std::filesystem::path out_dir;     ///< where CSV and charts go (created if missing)
  std::vector<std::string> options;  ///< remaining "--key value" words, command-specific
  bool quick = false;                ///< reduced sizes (used by tests), same code path
  bool no_chart = false;             ///< skip the chart script (CSV only)
  /// --progress (draw on stderr even when it is not a terminal), --no-progress (never);
  /// otherwise the progress line shows only on a terminal
  ProgressMode progress = ProgressMode::kAuto;

  /// Value of "--key" in options, or `fallback`.
  std::string option(const std::string& key, const std::string& fallback) const;
};

using CommandFn = std::function<int(const CommandArgs&)>;

struct CommandEntry {
  std::string name;
  std::string description;
  CommandFn run;
  std::vector<OptionSpec> options;  ///< what the command accepts besides --out, --quick, ...
};

class CommandRegistry {
 public:
  static CommandRegistry& get(const std::string& group);
  bool add(const std::string& name, const std::string& description, CommandFn fn,
           std::vector<OptionSpec> options = {});
  const CommandEntry* find(const std::string& name) const;
  std::vector<const CommandEntry*> list() const;

 private:
  std::map<std::string, CommandEntry> entries_;
};

/// Runs `script` (a file name in tests/charts/) with the system Python and its matplotlib:
///   /usr/bin/python3 <source>/tests/charts/<script> <args...>
/// Returns the exit status; prints a warning (does not throw) if the chart fails.
int run_chart_script(const std::string& script, const std::vector<std::string>& args);

/// Checks the words after the command name against `entry`'s options (see OptionSpec) and
/// fills `args`. @throws config::ConfigError naming the word, the value and the allowed range.
/// `--out` (required, once), `--quick`, `--no-chart`, `--progress` and `--no-progress` are
/// common to every command.
CommandArgs parse_command_args(const CommandEntry& entry, const std::vector<std::string>& words);

/// Shared main() of the tool executables: `<exe> <name> --out DIR [--quick] [--no-chart] ...`;
/// sets progress_mode() from --progress / --no-progress before the command runs.
/// A mistake on the command line exits 2 before the command runs (an unknown name or option
/// with the closest known one); `<name> --help`, `list`, `--help` and `--version` print and exit
/// 0 without running anything; --out is made (with its parents) or refused with exit 2.
int run_registry_main(const std::string& group, const std::string& exe, int argc, char** argv);

}  // namespace teleop

#define TELEOP_REGISTRY_CAT2(a, b) a##b
#define TELEOP_REGISTRY_CAT(a, b) TELEOP_REGISTRY_CAT2(a, b)
/// TELEOP_REGISTER_COMMAND(group, name, description, fn[, option specs...]): a command with no
/// option specs accepts only the common words (--out, --quick, --no-chart).
#define TELEOP_REGISTER_COMMAND(group, name, description, fn, ...)                       \
  static const bool TELEOP_REGISTRY_CAT(teleop_registered_, __LINE__) [[maybe_unused]] = \
      ::teleop::CommandRegistry::get(#group).add(name, description, fn, {__VA_ARGS__})
