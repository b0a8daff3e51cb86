#pragma once
// Paths and helpers shared by the multi-process integration tests (tests/integration/).
// TELEOP_BINARY_DIR and TELEOP_SOURCE_DIR are compile definitions of the test targets.
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "tests/support/json_fields.hpp"

namespace teleop::test {

/// The executables under test.
inline const std::string kServerBinary = std::string(TELEOP_BINARY_DIR) + "/server/teleop_server";
inline const std::string kMasterBinary = std::string(TELEOP_BINARY_DIR) + "/client/teleop_master";
inline const std::string kViewerBinary = std::string(TELEOP_BINARY_DIR) + "/client/teleop_viewer";

/// The exit status docs/exit_codes.md gives the verdict of a master's JSON summary (-1: none).
inline int verdict_exit_status(const std::string& summary_json) {
  const std::pair<const char*, int> statuses[] = {
      {"stable", 0}, {"degraded", 5}, {"oscillating", 6}, {"out-of-spec", 7}, {"unstable", 8}};
  const std::string verdict = json_text(summary_json, "verdict");
  for (const auto& [name, status] : statuses) {
    if (verdict == name) return status;
  }
  return -1;
}

/// A scene file of deploy/scenes/, e.g. scene_file("tool_only.yaml").
inline std::string scene_file(const std::string& name) {
  return std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/" + name;
}

/// A temporary path of this test process: <tmp>/teleop_<tag>_<pid>_<name>.
inline std::string temp_path(const std::string& tag, const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("teleop_" + tag + "_" + std::to_string(getpid()) + "_" + name))
      .string();
}

/// The fields of one line of CSV (no quoting).
inline std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> fields;
  for (std::size_t p = 0; p <= line.size();) {
    const auto c = line.find(',', p);
    fields.push_back(line.substr(p, c == std::string::npos ? std::string::npos : c - p));
    if (c == std::string::npos) break;
    p = c + 1;
  }
  return fields;
}

/// The numeric columns `names` of a CSV text with a header line, in order; a name the header
/// does not have gives an empty column.
inline std::vector<std::vector<double>> csv_columns(const std::string& csv,
                                                    const std::vector<std::string>& names) {
  std::istringstream in(csv);
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> header = split_csv_line(line);
  std::vector<std::size_t> idx;
  for (const auto& n : names) {
    idx.push_back(
        static_cast<std::size_t>(std::find(header.begin(), header.end(), n) - header.begin()));
  }
  std::vector<std::vector<double>> out(names.size());
  while (std::getline(in, line)) {
    const std::vector<std::string> fields = split_csv_line(line);
    for (std::size_t i = 0; i < idx.size(); ++i) {
      if (idx[i] < fields.size()) out[i].push_back(std::atof(fields[idx[i]].c_str()));
    }
  }
  return out;
}

}  // namespace teleop::test
