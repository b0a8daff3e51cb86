// Runs the deformable experiments and the benchmark in --quick --no-chart mode through their
// executables (skipped when they have not been built) and checks exit status and CSV output.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

namespace fs = std::filesystem;

int count_lines(const fs::path& p) {
  std::ifstream in(p);
  int n = 0;
  for (std::string line; std::getline(in, line);) ++n;
  return n;
}

struct Case {
  const char* exe;  // relative to the build directory
  const char* name;
  const char* csv;
  const char* header_start;
};

class ExperimentRuns : public ::testing::TestWithParam<Case> {};

TEST_P(ExperimentRuns, QuickRunWritesCsvAndSucceeds) {
  const Case c = GetParam();
  const fs::path exe = fs::path(TELEOP_BINARY_DIR) / c.exe;
  if (!fs::exists(exe)) GTEST_SKIP() << exe << " not built";
  const fs::path out = fs::temp_directory_path() /
                       ("teleop_deform_exp_" + std::to_string(::getpid()) + "_" + c.name);
  fs::remove_all(out);
  const std::string cmd = exe.string() + " " + c.name + " --quick --no-chart --out " +
                          out.string() + " > " + (out.string() + ".log") + " 2>&1";
  const int rc = std::system(cmd.c_str());
  EXPECT_EQ(rc, 0) << cmd;
  const fs::path csv = out / c.csv;
  ASSERT_TRUE(fs::exists(csv)) << csv;
  std::ifstream in(csv);
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header.rfind(c.header_start, 0), 0u) << header;
  EXPECT_GT(count_lines(csv), 10);
  for (const auto& entry : fs::directory_iterator(out)) {
    EXPECT_NE(entry.path().extension(), ".png") << "--no-chart must not draw: " << entry.path();
  }
  fs::remove_all(out);
  fs::remove(out.string() + ".log");
}

INSTANTIATE_TEST_SUITE_P(
    Deformable, ExperimentRuns,
    ::testing::Values(
        Case{"server/teleop_experiment", "sphere-zero-g", "sphere_zero_g.csv", "model,t_s"},
        Case{"server/teleop_experiment", "navier-free-vertex", "navier_free_vertex.csv",
             "variant,t_s"},
        Case{"server/teleop_experiment", "navier-held-vertex", "navier_held_vertex.csv",
             "model,t_s"},
        Case{"server/teleop_experiment", "sphere-gravity", "sphere_gravity.csv", "t_s,"},
        Case{"tests/bench/teleop_bench", "deformable", "deformable.csv",
             "model,integrator,kernel,level,nodes,elements,dt_s,substeps,step_us_median,"
             "step_us_p99,cost_steps,lamb_s2_pct,lamb_t2_pct,lamb_s0_pct,press_5mm_pct,"
             "error_pct"},
        Case{"tests/bench/teleop_bench", "growth", "growth.csv", "series,kind,level,n,"},
        Case{"tests/bench/teleop_bench", "peers", "peers.csv", "engine,level,nodes,dt_s,"}),
    [](const auto& param_info) {
      std::string n = param_info.param.name;
      for (char& ch : n) {
        if (ch == '-') ch = '_';
      }
      return n;
    });

}  // namespace
