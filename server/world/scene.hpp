#pragma once
// Scene files (deploy/scenes/*.yaml): what the server simulates and at which rates.
// Loading validates every field and throws config::ConfigError naming file, field, value
// and allowed range.
#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "common/config/config.hpp"
#include "server/world/plane.hpp"
#include "server/world/tool_scene.hpp"

namespace teleop::sim {

struct SceneConfig {
  std::string file;  ///< where it was loaded from
  std::string name = "tool-only";
  std::string kind = "tool";        ///< "tool" (free tool, no robot) or "robot"
  double physics_rate_hz = 1000.0;  ///< [Hz]
  double visual_rate_hz = 60.0;     ///< mesh frame rate [Hz]
  Eigen::Vector3d gravity_mps2{0.0, 0.0, -9.81};
  double command_timeout_s = 0.05;  ///< watchdog: hold when no valid command for this long [s]
  Eigen::Vector3d workspace_min_m{-1.5, -1.5, -0.1};  ///< commands outside are rejected [m]
  Eigen::Vector3d workspace_max_m{1.5, 1.5, 1.5};
  Eigen::Vector3d tool_start_m{0.6, 0.0, 0.7};  ///< initial tool/tip position [m]
  ToolModel tool;                               ///< tool-only scene parameters
  std::vector<Plane> planes;
  /// Raw sub-mappings for the parts that parse their own sections (robot, deformable bodies).
  std::optional<config::Node> robot_node;
  std::vector<config::Node> deformable_nodes;
};

/// Loads and validates a scene file. @throws config::ConfigError.
SceneConfig load_scene(const std::string& file);
/// Parses scene YAML text (`file` used in messages). @throws config::ConfigError.
SceneConfig parse_scene(const config::Node& root);

}  // namespace teleop::sim
