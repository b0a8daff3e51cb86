// The folder rules of docs/conventions.md, checked on the sources: client/ and server/ never
// include each other; the observers' folders never include the control loop; common/ includes
// neither side.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

/// Every `#include "..."` under `folder` that starts with one of `forbidden`, as "file: include".
/// Files under the folders of `skip` (relative to the source root) are not looked at.
std::vector<std::string> offending_includes(const std::string& folder,
                                            const std::vector<std::string>& forbidden,
                                            const std::vector<std::string>& skip = {}) {
  std::vector<std::string> found;
  const fs::path root = fs::path(TELEOP_SOURCE_DIR) / folder;
  const std::regex include_re(R"re(^\s*#\s*include\s+"([^"]+)")re");
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    const std::string ext = entry.path().extension().string();
    if (!entry.is_regular_file() || (ext != ".cpp" && ext != ".hpp" && ext != ".h")) continue;
    const std::string rel = fs::relative(entry.path(), TELEOP_SOURCE_DIR).string();
    bool skipped = false;
    for (const std::string& k : skip) skipped = skipped || rel.rfind(k, 0) == 0;
    if (skipped) continue;
    std::ifstream in(entry.path());
    std::smatch m;
    for (std::string line; std::getline(in, line);) {
      if (!std::regex_search(line, m, include_re)) continue;
      for (const std::string& f : forbidden) {
        if (m[1].str().rfind(f, 0) == 0) {
          found.push_back(fs::relative(entry.path(), TELEOP_SOURCE_DIR).string() + ": " +
                          m[1].str());
        }
      }
    }
  }
  return found;
}

std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += "\n  " + x;
  return s;
}

// client/ and server/ never include each other, with no exception: the programs that run both
// halves in one process (teleop_campaign, the Python module) reach the server's world through
// common/harness/in_process.hpp, defined by server/harness/ (teleop::world_harness). Nothing in
// client/ or server/ includes client/campaign/ except client/python/ (the Python module, which
// gives the campaigns and the world step to Python).
TEST(Layering, ClientAndServerNeverIncludeEachOther) {
  const auto client = offending_includes("client", {"server/"});
  EXPECT_TRUE(client.empty()) << "client/ includes server/:" << joined(client);
  const auto server = offending_includes("server", {"client/"});
  EXPECT_TRUE(server.empty()) << "server/ includes client/:" << joined(server);
  const auto campaign =
      offending_includes("client", {"client/campaign/"}, {"client/campaign/", "client/python/"});
  EXPECT_TRUE(campaign.empty()) << "client/ includes client/campaign/:" << joined(campaign);
}

TEST(Layering, CommonIncludesNeitherSide) {
  const auto common = offending_includes("common", {"server/", "client/"});
  EXPECT_TRUE(common.empty()) << "common/ includes a side:" << joined(common);
}

TEST(Layering, ObserversNeverIncludeTheControlLoop) {
  for (const char* folder : {"client/record", "client/monitor", "client/viewer", "client/bridge"}) {
    const auto bad = offending_includes(
        folder, {"client/control/", "client/cycle/", "client/sim/", "client/node/"});
    EXPECT_TRUE(bad.empty()) << folder << " includes the control loop:" << joined(bad);
  }
}

TEST(Layering, TheInProcessHarnessIsNotUsedByTheMasterNode) {
  const auto node = offending_includes("client/node", {"client/sim/", "client/analysis/"});
  EXPECT_TRUE(node.empty()) << "client/node includes the harness:" << joined(node);
}

}  // namespace
