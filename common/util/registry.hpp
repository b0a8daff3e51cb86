#pragma once
// Named sub-commands for the tool executables (teleop_experiment, teleop_bench).
// A .cpp linked directly into the executable registers itself with
//   TELEOP_REGISTER_COMMAND(experiments, "sphere-zero-g", "experiment 1 ...", run_fn);
// where run_fn is `int (const teleop::CommandArgs&)`.
#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

namespace teleop {

struct CommandArgs {
  std::filesystem::path out_dir;     ///< where CSV and charts go (created if missing)
  std::vector<std::string> options;  ///< remaining "--key value" words, command-specific
  bool quick = false;                ///< reduced sizes (used by tests), same code path
  bool no_chart = false;             ///< skip the chart script (CSV only)

  /// Value of "--key" in options, or `fallback`.
  std::string option(const std::string& key, const std::string& fallback) const;
};

using CommandFn = std::function<int(const CommandArgs&)>;

struct CommandEntry {
  std::string name;
  std::string description;
  CommandFn run;
};

class CommandRegistry {
 public:
  static CommandRegistry& get(const std::string& group);
  bool add(const std::string& name, const std::string& description, CommandFn fn);
  const CommandEntry* find(const std::string& name) const;
  std::vector<const CommandEntry*> list() const;

 private:
  std::map<std::string, CommandEntry> entries_;
};

/// Runs `script` (a file name in tests/charts/) with the system Python and its matplotlib:
///   /usr/bin/python3 <source>/tests/charts/<script> <args...>
/// Returns the exit status; prints a warning (does not throw) if the chart fails.
int run_chart_script(const std::string& script, const std::vector<std::string>& args);

/// Shared main() of the tool executables: `<exe> <name> --out DIR [--quick] [--no-chart] ...`.
int run_registry_main(const std::string& group, const std::string& exe, int argc, char** argv);

}  // namespace teleop

#define TELEOP_REGISTRY_CAT2(a, b) a##b
#define TELEOP_REGISTRY_CAT(a, b) TELEOP_REGISTRY_CAT2(a, b)
#define TELEOP_REGISTER_COMMAND(group, name, description, fn)                            \
  static const bool TELEOP_REGISTRY_CAT(teleop_registered_, __LINE__) [[maybe_unused]] = \
      ::teleop::CommandRegistry::get(#group).add(name, description, fn)
