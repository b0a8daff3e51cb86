// Every stiffness and gain of a scene at both ends of its allowed range: the scene is either
// refused at load with a message that names the field, or a default session on it (homing, then
// the press-slip script into the sphere or onto the floor) runs without a single world fault.
// The ranges are the loader's own: each is read from the message the loader gives for a value
// far outside it, so the test follows the configuration as it changes.
#include <gtest/gtest.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "client/campaign/campaign.hpp"
#include "client/campaign/results.hpp"
#include "common/config/config.hpp"
#include "server/world/world_model.hpp"
#include "tests/support/config_error.hpp"

namespace teleop::campaign {
namespace {

namespace fs = std::filesystem;

const std::string kScenes = std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/";

/// One stiffness or gain of a scene: which scene, where in it, and how to set it.
struct Field {
  std::string scene;  ///< "default.yaml", "paper_sphere.yaml" (robot) or "tool_only.yaml" (tool)
  std::string name;   ///< as the loader names it (the last key)
  /// Sets the field to `value` in the scene's root and the robot file's root.
  std::function<void(YAML::Node& scene, YAML::Node& robot, double value)> set;
};

std::vector<Field> fields() {
  std::vector<Field> out;
  const auto body = [&](const std::string& scene, const std::string& key) {
    out.push_back({scene, key, [key](YAML::Node& s, YAML::Node&, double v) {
                     s["deformables"][0]["body"][key] = v;
                   }});
  };
  // the paper's mass-spring sphere: its contact block and its springs
  for (const char* k : {"stiffness_n_per_m", "damping_ns_per_m", "node_stiffness_n_per_m",
                        "node_damping_ns_per_m"}) {
    const std::string key = k;
    out.push_back({"paper_sphere.yaml", key, [key](YAML::Node& s, YAML::Node&, double v) {
                     s["deformables"][0]["contact"][key] = v;
                   }});
  }
  for (const char* k :
       {"youngs_modulus_pa", "radial_stiffness_n_per_m3", "stiffness_damping_s", "radial_damping_s",
        "mass_damping_per_s", "contact_frequency_rad_per_s", "contact_damping_ratio"}) {
    body("paper_sphere.yaml", k);
  }
  // the default scene's FEM ball: its material, damping and contact
  for (const char* k : {"youngs_modulus_pa", "poisson_ratio", "stiffness_damping_s",
                        "mass_damping_per_s", "contact_pressure_stiffness_pa_per_m",
                        "contact_frequency_rad_per_s", "contact_damping_ratio"}) {
    body("default.yaml", k);
  }
  for (const std::string& scene : {std::string("default.yaml"), std::string("tool_only.yaml")}) {
    for (const char* k : {"stiffness_n_per_m", "damping_ns_per_m"}) {
      const std::string key = k;
      out.push_back({scene, key, [key](YAML::Node& s, YAML::Node&, double v) {
                       for (std::size_t i = 0; i < s["planes"].size(); ++i) s["planes"][i][key] = v;
                     }});
    }
  }
  out.push_back({"default.yaml", "gain_per_s",
                 [](YAML::Node&, YAML::Node& r, double v) { r["robot"]["ik"]["gain_per_s"] = v; }});
  for (const char* k : {"kp_nm_per_rad", "kd_nms_per_rad", "viscous_nms_per_rad"}) {
    const std::string key = k;
    out.push_back({"default.yaml", key, [key](YAML::Node&, YAML::Node& r, double v) {
                     for (std::size_t i = 0; i < r["robot"]["links"].size(); ++i) {
                       r["robot"]["links"][i]["joint"][key] = v;
                     }
                   }});
  }
  for (const char* k : {"kp_n_per_m", "kd_ns_per_m", "kp_rot_nm_per_rad", "kd_rot_nms_per_rad",
                        "linear_damping_ns_per_m"}) {
    const std::string key = k;
    out.push_back({"tool_only.yaml", key,
                   [key](YAML::Node& s, YAML::Node&, double v) { s["tool"][key] = v; }});
  }
  return out;
}

class SceneCorners : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("teleop_corners_" + std::to_string(getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  /// Writes the scene of `f` with the field at `value` (and its robot file beside it); returns
  /// the scene's path.
  std::string write_scene(const Field& f, double value) {
    YAML::Node scene = YAML::LoadFile(kScenes + f.scene);
    YAML::Node robot = YAML::LoadFile(kScenes + "robot_puma560.yaml");
    robot["robot"]["source"] = "the PUMA 560 of deploy/scenes";  // the emitter leaves '&' plain
    f.set(scene, robot, value);
    emit(robot, dir_ / "robot_puma560.yaml");
    const fs::path p = dir_ / f.scene;
    emit(scene, p);
    return p.string();
  }

  static void emit(const YAML::Node& n, const fs::path& p) {
    YAML::Emitter e;
    e.SetDoublePrecision(17);
    e << n;
    std::ofstream(p) << e.c_str() << "\n";
  }

  fs::path dir_;
};

/// The allowed range the loader states for the field (asked with a value far outside it).
bool range_of(const std::string& scene, double& lo, double& hi) {
  const std::string msg = test::config_error_of([&] { sim::load_world_model(scene); });
  static const std::regex re(R"(allowed range \[([^,\]]+), ([^\]]+)\])");
  std::smatch m;
  if (!std::regex_search(msg, m, re)) return false;
  lo = std::stod(m[1].str());
  hi = std::stod(m[2].str());
  return true;
}

/// The cell `name` of a run's row.
std::string cell(const Campaign& c, const std::string& row, const std::string& name) {
  std::vector<std::string> names, cells;
  std::stringstream h(results_header(c)), r(row);
  for (std::string x; std::getline(h, x, ',');) names.push_back(x);
  for (std::string x; std::getline(r, x, ',');) cells.push_back(x);
  const auto it = std::find(names.begin(), names.end(), name);
  const auto i = static_cast<std::size_t>(it - names.begin());
  return it == names.end() || i >= cells.size() ? "?" : cells[i];
}

TEST_F(SceneCorners, EveryStiffnessAndGainAtEitherEndIsRefusedAtLoadOrRunsWithoutFaults) {
  int refused = 0, ran = 0;
  for (const Field& f : fields()) {
    double lo = 0.0, hi = 0.0;
    const std::string probe = write_scene(f, -1e300);
    ASSERT_TRUE(range_of(probe, lo, hi))
        << f.scene << " " << f.name << ": "
        << test::config_error_of([&] { sim::load_world_model(probe); });
    for (const double v : {lo, hi}) {
      const std::string scene = write_scene(f, v);
      const std::string what = f.scene + " " + f.name + " " + std::to_string(v);
      std::string error;
      Campaign c;
      try {
        c = parse_campaign(
            "name: corner\nmodel: world\nduration_s: 3\nhoming_s: 1\n"
            "sweeps:\n  - name: s\n    scene: " +
                scene + "\n",
            (dir_ / "corner.yaml").string());
      } catch (const config::ConfigError& e) {
        error = e.what();
      }
      if (!error.empty()) {
        // refused at load: the message names the scene file and the field
        ++refused;
        EXPECT_NE(error.find(scene), std::string::npos) << what << ": " << error;
        EXPECT_NE(error.find(f.name), std::string::npos) << what << ": " << error;
        std::printf("[ refused  ] %s: %.200s\n", what.c_str(), error.c_str());
        continue;
      }
      ++ran;
      const auto t0 = std::chrono::steady_clock::now();
      const std::string row = run_one(c, c.runs.at(0));
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::printf("[ ran      ] %s: faults %s, verdict %s, contact %s s (%.2f s)\n", what.c_str(),
                  cell(c, row, "world_faults").c_str(), cell(c, row, "verdict").c_str(),
                  cell(c, row, "contact_time_s").c_str(), s);
      EXPECT_NE(cell(c, row, "verdict"), "error") << what << ": " << row;
      EXPECT_EQ(cell(c, row, "world_faults"), "0") << what << ": " << row;
    }
  }
  // both outcomes occur: the stiffest corners are refused, the softest run
  EXPECT_GT(refused, 0);
  EXPECT_GT(ran, 0);
}

/// The controller's gain (position-position: K_pm = K_ps, which the slave's tracking law takes as
/// its stiffness) at both ends of the campaign's range, on both shipped kinds of scene.
TEST_F(SceneCorners, TheControllerGainAtEitherEndRunsWithoutFaults) {
  const auto campaign = [](const std::string& scene, const std::string& gain) {
    return "name: gain\nmodel: world\nduration_s: 3\nhoming_s: 1\nsweeps:\n  - name: s\n"
           "    scheme: position-position\n    scene: " +
           scene + "\n    gain: " + gain + "\n";
  };
  const std::string tool = kScenes + "tool_only.yaml";
  double lo = 0.0, hi = 0.0;
  {
    const std::string msg =
        test::config_error_of([&] { parse_campaign(campaign(tool, "-1e300"), "gain.yaml"); });
    static const std::regex re(R"(allowed range \[([^,\]]+), ([^\]]+)\])");
    std::smatch m;
    ASSERT_TRUE(std::regex_search(msg, m, re)) << msg;
    lo = std::stod(m[1].str());
    hi = std::stod(m[2].str());
  }
  for (const std::string& scene : {tool, kScenes + "default.yaml", kScenes + "paper_sphere.yaml"}) {
    for (const double g : {lo, hi}) {
      std::ostringstream gain;
      gain << g;
      const Campaign c = parse_campaign(campaign(scene, gain.str()), "gain.yaml");
      const std::string row = run_one(c, c.runs.at(0));
      std::printf("[ ran      ] %s gain %s: faults %s, verdict %s\n", scene.c_str(),
                  gain.str().c_str(), cell(c, row, "world_faults").c_str(),
                  cell(c, row, "verdict").c_str());
      EXPECT_EQ(cell(c, row, "world_faults"), "0") << scene << " gain " << g << ": " << row;
      EXPECT_NE(cell(c, row, "verdict"), "error") << scene << " gain " << g << ": " << row;
    }
  }
}

}  // namespace
}  // namespace teleop::campaign
