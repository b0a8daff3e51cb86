// libFuzzer target: the scene loader on arbitrary text, parse_world_model(Node::parse(text)), the
// path every scene file takes (YAML checks, every field, robot include, deformable bodies with
// their meshes and stability estimate, world box, rate check). A config::ConfigError is the
// loader's answer to bad input (exit status 2 in the apps); anything else that escapes (another
// exception, a crash, a sanitizer report, a hang) is a bug.
//
// The text is parsed as if it were a file in deploy/scenes/, so `include: robot_puma560.yaml`
// and relative mesh paths resolve as they do for the shipped scenes.
#include <cstddef>
#include <cstdint>
#include <string>

#include "server/world/world_model.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string kFile = std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/fuzz.yaml";
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const teleop::sim::WorldModel m =
        teleop::sim::parse_world_model(teleop::config::Node::parse(text, kFile));
    (void)teleop::sim::physics_rate_notes(m, m.physics_rate_hz);
    (void)teleop::sim::min_physics_rate_hz(m);
  } catch (const teleop::config::ConfigError&) {
  }
  return 0;
}
