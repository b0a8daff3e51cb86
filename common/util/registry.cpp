#include "common/util/registry.hpp"

#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <iostream>

#include "common/config/config.hpp"

#ifndef TELEOP_SOURCE_DIR
#define TELEOP_SOURCE_DIR "."
#endif
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

bool CommandRegistry::add(const std::string& name, const std::string& description, CommandFn fn) {
  entries_[name] = CommandEntry{name, description, std::move(fn)};
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
  std::string cmd = std::string(TELEOP_PYTHON3) + " " +
                    shell_quote(std::string(TELEOP_SOURCE_DIR) + "/tests/charts/" + script);
  for (const auto& a : args) cmd += " " + shell_quote(a);
  const int rc = std::system(cmd.c_str());
  const int status = rc == -1 ? -1 : (WIFEXITED(rc) ? WEXITSTATUS(rc) : -1);
  if (status != 0) {
    std::cerr << "warning: chart script " << script << " failed (status " << status << ")\n";
  }
  return status;
}

namespace {
void usage(const std::string& group, const std::string& exe, std::ostream& os) {
  os << "usage: " << exe << " <name> --out DIR [--quick] [--no-chart] [command options]\n\n"
     << "names:\n";
  for (const auto* e : CommandRegistry::get(group).list()) {
    os << "  " << e->name << std::string(e->name.size() < 24 ? 24 - e->name.size() : 1, ' ')
       << e->description << "\n";
  }
}
}  // namespace

int run_registry_main(const std::string& group, const std::string& exe, int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
    usage(group, exe, argc < 2 ? std::cerr : std::cout);
    return argc < 2 ? 2 : 0;
  }
  const std::string name = argv[1];
  const CommandEntry* entry = CommandRegistry::get(group).find(name);
  if (!entry) {
    std::cerr << exe << ": unknown name '" << name << "'\n";
    usage(group, exe, std::cerr);
    return 2;
  }
  CommandArgs args;
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--out" && i + 1 < argc) {
      args.out_dir = argv[++i];
    } else if (a == "--quick") {
      args.quick = true;
    } else if (a == "--no-chart") {
      args.no_chart = true;
    } else {
      args.options.push_back(a);
    }
  }
  if (args.out_dir.empty()) {
    std::cerr << exe << " " << name << ": --out DIR is required\n";
    return 2;
  }
  try {
    std::filesystem::create_directories(args.out_dir);
    return entry->run(args);
  } catch (const config::ConfigError& e) {
    std::cerr << exe << " " << name << ": " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << exe << " " << name << ": error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace teleop
