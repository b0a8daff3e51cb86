#pragma once
// Which build made a program, a summary or a recording: the project version (CMakeLists.txt)
// and the git revision of the source tree at configure time ("unknown" when the tree is not a
// git checkout or git is missing; CMake configures again when the checkout's HEAD moves).
#include <string>

namespace teleop {

/// "0.1.0".
const char* project_version();
/// "1a2b3c4d5e6f" (12 hex digits), or "unknown".
const char* git_revision();
/// "0.1.0 (git 1a2b3c4d5e6f)": the value of "version" in every summary JSON.
std::string version_string();
/// "<exe> 0.1.0 (git 1a2b3c4d5e6f)": what `--version` prints.
std::string version_line(const std::string& exe);

}  // namespace teleop
