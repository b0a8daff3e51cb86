#include "common/util/data_dir.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

namespace fs = std::filesystem;

/// Sets TELEOP_DATA_DIR for one test and removes it after.
class DataDirTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() / ("teleop_data_dir_" + std::to_string(::getpid()));
    fs::create_directories(root_ / "scenes");
    std::ofstream(root_ / "scenes" / "mine.yaml") << "name: mine\n";
  }
  void TearDown() override {
    ::unsetenv("TELEOP_DATA_DIR");
    fs::remove_all(root_);
  }
  fs::path root_;
};

TEST_F(DataDirTest, AnInstalledTreeNamedByTheEnvironmentComesFirst) {
  ::setenv("TELEOP_DATA_DIR", root_.c_str(), 1);
  EXPECT_EQ(teleop::data_path("scenes/mine.yaml"), (root_ / "scenes" / "mine.yaml").string());
}

TEST_F(DataDirTest, AFolderTheInstalledTreeLacksComesFromTheSourceTree) {
  // the tree named has scenes/ only: profiles and charts come from the source tree
  ::setenv("TELEOP_DATA_DIR", root_.c_str(), 1);
  const std::string profiles = teleop::data_path("profiles/loopback.xml");
  EXPECT_EQ(profiles, std::string(TELEOP_SOURCE_DIR) + "/deploy/profiles/loopback.xml");
  EXPECT_TRUE(fs::is_regular_file(profiles));
  const std::string chart = teleop::data_path("charts/session.py");
  EXPECT_EQ(chart, std::string(TELEOP_SOURCE_DIR) + "/tests/charts/session.py");
  EXPECT_TRUE(fs::is_regular_file(chart));
}

TEST_F(DataDirTest, ABuildTreeProgramReadsTheSourceTree) {
  // no TELEOP_DATA_DIR, and this test program lives in the build tree
  for (const std::string rel : {"scenes/default.yaml", "data/deformable.csv",
                                "reference/calculix/ball_reference.csv", "data/tet"}) {
    const std::string p = teleop::data_path(rel);
    EXPECT_EQ(p.rfind(std::string(TELEOP_SOURCE_DIR) + "/", 0), 0u) << p;
    EXPECT_TRUE(fs::exists(p)) << p;
  }
}

TEST_F(DataDirTest, AnEmptyVariableIsIgnored) {
  ::setenv("TELEOP_DATA_DIR", "", 1);
  EXPECT_EQ(teleop::data_path("scenes/default.yaml"),
            std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/default.yaml");
}

}  // namespace
