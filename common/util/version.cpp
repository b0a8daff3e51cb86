#include "common/util/version.hpp"

#include "teleop_build_version.hpp"

namespace teleop {

const char* project_version() { return TELEOP_PROJECT_VERSION; }

const char* git_revision() { return TELEOP_GIT_REVISION; }

std::string version_string() {
  return std::string(project_version()) + " (git " + git_revision() + ")";
}

std::string version_line(const std::string& exe) { return exe + " " + version_string(); }

}  // namespace teleop
