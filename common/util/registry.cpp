#include "common/util/registry.hpp"

#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <optional>

#include "common/config/config.hpp"
#include "common/config/suggest.hpp"
#include "common/util/data_dir.hpp"
#include "common/util/files.hpp"
#include "common/util/version.hpp"

#ifndef TELEOP_PYTHON3
#define TELEOP_PYTHON3 "/usr/bin/python3"
#endif

namespace teleop {

std::string CommandArgs::option(const std::string& key, const std::string& fallback) const {
  for (std::size_t i = 0; i + 1 < options.size(); ++i) {
    if (options[i] == key) return options[i + 1];
  }
  return fallback;
}

CommandRegistry& CommandRegistry::get(const std::string& group) {
  static std::map<std::string, CommandRegistry> groups;
  return groups[group];
}

bool CommandRegistry::add(const std::string& name, const std::string& description, CommandFn fn,
                          std::vector<OptionSpec> options) {
  entries_[name] = CommandEntry{name, description, std::move(fn), std::move(options)};
  return true;
}

const CommandEntry* CommandRegistry::find(const std::string& name) const {
  auto it = entries_.find(name);
  return it == entries_.end() ? nullptr : &it->second;
}

std::vector<const CommandEntry*> CommandRegistry::list() const {
  std::vector<const CommandEntry*> out;
  for (const auto& kv : entries_) out.push_back(&kv.second);
  return out;
}

namespace {
std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'') {
      out += "'\\''";
    } else {
      out += c;
    }
  }
  return out + "'";
}
}  // namespace

int run_chart_script(const std::string& script, const std::vector<std::string>& args) {
  std::string cmd = std::string(TELEOP_PYTHON3) + " " + shell_quote(data_path("charts/" + script));
  for (const auto& a : args) cmd += " " + shell_quote(a);
  const int rc = std::system(cmd.c_str());
  const int status = rc == -1 ? -1 : (WIFEXITED(rc) ? WEXITSTATUS(rc) : -1);
  if (status != 0) {
    std::cerr << "warning: chart script " << script << " failed (status " << status << ")\n";
  }
  return status;
}

namespace {
std::string option_usage(const OptionSpec& o) {
  std::string v = o.name;
  if (o.kind == OptionSpec::Kind::kText) {
    v += " TEXT";
  } else {
    v += (o.kind == OptionSpec::Kind::kInteger ? " INTEGER in " : " NUMBER in ") +
         config::range_text(o.lo, o.hi);
  }
  return v;
}

/// One command: its name, description and options.
void command_usage(const CommandEntry& e, std::ostream& os) {
  os << "  " << e.name << std::string(e.name.size() < 24 ? 24 - e.name.size() : 1, ' ')
     << e.description << "\n";
  for (const OptionSpec& o : e.options) {
    os << "      " << option_usage(o) << (o.help.empty() ? "" : ": " + o.help) << "\n";
  }
}

void usage(const std::string& group, const std::string& exe, std::ostream& os) {
  os << "usage: " << exe
     << " <name> --out DIR [--quick] [--no-chart] [--progress | --no-progress]"
        " [command options]\n"
     << "       " << exe << " <name> --help\n"
     << "       " << exe << " list | --help | --version\n\n"
     << "names:\n";
  for (const auto* e : CommandRegistry::get(group).list()) command_usage(*e, os);
}

std::vector<std::string> option_names(const CommandEntry& entry) {
  std::vector<std::string> names = {"--out",      "--quick",       "--no-chart",
                                    "--progress", "--no-progress", "--help"};
  for (const OptionSpec& o : entry.options) names.push_back(o.name);
  return names;
}

std::string known_options(const CommandEntry& entry) {
  std::string list;
  for (const std::string& n : option_names(entry)) list += (list.empty() ? "" : ", ") + n;
  return list;
}

std::vector<std::string> command_names(const std::string& group) {
  std::vector<std::string> names;
  for (const auto* e : CommandRegistry::get(group).list()) names.push_back(e->name);
  return names;
}
}  // namespace

CommandArgs parse_command_args(const CommandEntry& entry, const std::vector<std::string>& words) {
  CommandArgs args;
  std::vector<std::string> seen;
  bool have_out = false;
  for (std::size_t i = 0; i < words.size(); ++i) {
    std::string key = words[i];
    std::optional<std::string> value;
    if (const auto eq = key.find('='); key.rfind("--", 0) == 0 && eq != std::string::npos) {
      value = key.substr(eq + 1);
      key = key.substr(0, eq);
    }
    if (key == "--quick" || key == "--no-chart") {
      if (value) throw config::ConfigError("command line: " + key + " takes no value");
      (key == "--quick" ? args.quick : args.no_chart) = true;
      continue;
    }
    if (key == "--progress" || key == "--no-progress") {
      if (value) throw config::ConfigError("command line: " + key + " takes no value");
      args.progress = key == "--progress" ? ProgressMode::kOn : ProgressMode::kOff;
      continue;
    }
    const OptionSpec* spec = nullptr;
    for (const OptionSpec& o : entry.options) {
      if (o.name == key) spec = &o;
    }
    if (key != "--out" && !spec) {
      throw config::ConfigError("command line: '" + key + "' is not an option of " + entry.name +
                                config::did_you_mean(key, option_names(entry)) +
                                " (its options: " + known_options(entry) + ")");
    }
    if (!value) {
      if (i + 1 >= words.size())
        throw config::ConfigError("command line: " + key + " needs a value");
      value = words[++i];
    }
    if (std::find(seen.begin(), seen.end(), key) != seen.end()) {
      throw config::ConfigError("command line: " + key + " is given more than once");
    }
    seen.push_back(key);
    if (value->empty()) {
      throw config::ConfigError("command line: " + key + " '' is empty; a value is needed");
    }
    if (key == "--out") {
      args.out_dir = *value;
      have_out = true;
      continue;
    }
    if (spec->kind != OptionSpec::Kind::kText) {
      const std::string problem = config::number_problem(*value, spec->lo, spec->hi,
                                                         spec->kind == OptionSpec::Kind::kInteger);
      if (!problem.empty()) throw config::ConfigError("command line: " + key + " " + problem);
    }
    args.options.push_back(key);
    args.options.push_back(*value);
  }
  if (!have_out) throw config::ConfigError("command line: --out DIR is required");
  return args;
}

namespace {
/// `<exe> <name> ... --help`: the words ask for the command's help (nothing runs).
bool wants_help(const std::vector<std::string>& words) {
  return std::find(words.begin(), words.end(), "--help") != words.end() ||
         std::find(words.begin(), words.end(), "-h") != words.end();
}
}  // namespace

int run_registry_main(const std::string& group, const std::string& exe, int argc, char** argv) {
  const std::string first = argc < 2 ? "" : argv[1];
  if (argc < 2 || first == "--help" || first == "-h") {
    usage(group, exe, argc < 2 ? std::cerr : std::cout);
    return argc < 2 ? 2 : 0;
  }
  if (first == "--version" && argc == 2) {
    std::cout << version_line(exe) << "\n";
    return 0;
  }
  if (first == "list" && argc == 2) {
    for (const std::string& n : command_names(group)) std::cout << n << "\n";
    return 0;
  }
  const CommandEntry* entry = CommandRegistry::get(group).find(first);
  if (!entry) {
    std::cerr << exe << ": unknown name '" << first << "'"
              << config::did_you_mean(first, command_names(group)) << " (`" << exe
              << " list` lists them)\n";
    return 2;
  }
  const std::string& name = first;
  const std::vector<std::string> words(argv + 2, argv + argc);
  if (wants_help(words)) {  // help for the command; nothing runs
    std::cout << "usage: " << exe << " " << name
              << " --out DIR [--quick] [--no-chart] [--progress | --no-progress] [options]\n";
    command_usage(*entry, std::cout);
    return 0;
  }
  try {
    const CommandArgs args = parse_command_args(*entry, words);
    set_progress_mode(args.progress);
    prepare_output_dir("--out", args.out_dir.string());
    const int status = entry->run(args);
    const std::vector<std::string> failed = failed_writes();
    for (const std::string& f : failed) std::cerr << exe << " " << name << ": error: " << f << "\n";
    return failed.empty() ? status : 1;
  } catch (const config::ConfigError& e) {
    std::cerr << exe << " " << name << ": " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << exe << " " << name << ": error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace teleop
