#include "common/util/data_dir.hpp"

#include <cstdlib>
#include <filesystem>
#include <system_error>
#include <utility>
#include <vector>

#ifndef TELEOP_SOURCE_DIR
#define TELEOP_SOURCE_DIR "."
#endif
#ifndef TELEOP_INSTALL_DATA_DIR
#define TELEOP_INSTALL_DATA_DIR "/usr/local/share/teleop"
#endif
#ifndef TELEOP_BUILD_DIR
#define TELEOP_BUILD_DIR "/nonexistent"
#endif
#ifndef TELEOP_BIN_TO_DATA_DIR
#define TELEOP_BIN_TO_DATA_DIR "../share/teleop"
#endif

namespace teleop {

namespace fs = std::filesystem;

namespace {

/// The installed layout's first component and where the source tree keeps the same folder.
const std::vector<std::pair<std::string, std::string>>& source_folders() {
  static const std::vector<std::pair<std::string, std::string>> folders = {
      {"scenes", "deploy/scenes"}, {"profiles", "deploy/profiles"},  {"data", "deploy/data"},
      {"charts", "tests/charts"},  {"reference", "tests/reference"},
  };
  return folders;
}

std::string first_component(const std::string& relative) {
  const auto slash = relative.find('/');
  return slash == std::string::npos ? relative : relative.substr(0, slash);
}

bool is_dir(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

bool is_inside(const fs::path& p, const fs::path& dir) {
  const fs::path rel = p.lexically_relative(dir);
  return !rel.empty() && *rel.begin() != "..";
}

/// The installed data folders to try, in order. A program of the build tree skips the
/// configured install prefix: it reads the source tree it was built from.
std::vector<fs::path> installed_roots() {
  std::vector<fs::path> roots;
  if (const char* env = std::getenv("TELEOP_DATA_DIR"); env != nullptr && *env != '\0') {
    roots.emplace_back(env);
  }
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) roots.push_back((exe.parent_path() / TELEOP_BIN_TO_DATA_DIR).lexically_normal());
  if (ec || !is_inside(exe, TELEOP_BUILD_DIR)) roots.emplace_back(TELEOP_INSTALL_DATA_DIR);
  return roots;
}

}  // namespace

std::string data_path(const std::string& relative) {
  const std::string first = first_component(relative);
  for (const auto& root : installed_roots()) {
    if (is_dir(root / first)) return (root / relative).string();
  }
  const std::string rest = relative.size() > first.size() ? relative.substr(first.size()) : "";
  for (const auto& [installed, source] : source_folders()) {
    if (installed == first) return std::string(TELEOP_SOURCE_DIR) + "/" + source + rest;
  }
  return std::string(TELEOP_SOURCE_DIR) + "/" + relative;
}

}  // namespace teleop
