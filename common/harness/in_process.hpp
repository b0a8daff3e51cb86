#pragma once
// The server's world run in the client's process, as the programs that run both halves see it
// (teleop_campaign, the Python module, the tests): a loaded scene, the server's physics period
// as an in-process slave for LoopbackSession, and a scene's world stepped off-line. Everything
// here is declared with common/ types only; the one definition is the server's binding,
// server/harness/in_process.cpp (target teleop::world_harness, linking teleop::sim), so a
// client folder uses the server's world without including a server header.
//
//   std::shared_ptr<const SceneModel> scene = load_scene_model("deploy/scenes/default.yaml");
//   std::unique_ptr<InProcessSlave> slave =
//       make_world_slave(*scene, 1.0 / scene_physics_rate_hz(*scene));
//   LoopbackSession session(cfg, device, *slave);  // steps it through SlaveSimulator
#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "common/control/slave_simulator.hpp"
#include "common/sim/events.hpp"
#include "common/sim/tool.hpp"
#include "teleop/idl/Teleop.h"

namespace teleop::harness {

/// A loaded scene: the server's immutable world model (opaque here), shared by every slave and
/// world made from it.
struct SceneModel;

/// Loads and validates a scene file with the server's loader (docs/configuration.md).
/// @throws config::ConfigError naming the file, the field, the value and the allowed range.
std::shared_ptr<const SceneModel> load_scene_model(const std::string& file);
/// The file the scene was loaded from, as given to load_scene_model.
const std::string& scene_file(const SceneModel& scene);
/// The scene's name (its `name:` field).
const std::string& scene_name(const SceneModel& scene);
/// The rate the scene's physics runs at [Hz].
double scene_physics_rate_hz(const SceneModel& scene);
/// The scene as the server publishes it on teleop/scene, for its world as loaded.
SceneDescription describe_scene(const SceneModel& scene);

/// The server's physics period as an in-process slave (the ServerCycle teleop_server runs:
/// command watchdog, passivity port, world_step, contact estimate). step() allocates nothing.
/// sample() is one object for the slave's lifetime: a reference taken once stays current.
class InProcessSlave : public SlaveSimulator {
 public:
  /// Times the command watchdog held the slave since the last reset.
  virtual std::uint64_t watchdog_trips() const = 0;
  /// Events the world and the watchdog raised since the last reset, of one kind.
  virtual std::uint64_t events_of(sim::EventKind kind) const = 0;
  /// The scene as the server would publish it for this slave's world now.
  virtual SceneDescription describe_scene() const = 0;
};

/// A slave stepping `scene`'s world (a copy of its model) with period dt_s [s]; the command
/// watchdog uses the scene's command_timeout_s.
std::unique_ptr<InProcessSlave> make_world_slave(const SceneModel& scene, double dt_s);
/// A slave stepping the tool-only world of `tool` (its obstacles as the world's planes and
/// spheres) at 1 / dt_s, the tool starting at `start_m` [m].
std::unique_ptr<InProcessSlave> make_tool_slave(const sim::ToolModel& tool,
                                                const Eigen::Vector3d& start_m, double dt_s);

/// Facts of one deformable body's model.
struct BodyInfo {
  std::string model;  ///< the body's model kind ("mass-spring", "fem", ...)
  int surface_node_count = 0;
  int node_count = 0;  ///< columns of nodes(): surface nodes, then interior nodes (fem)
  int triangle_count = 0;
  double total_mass_kg = 0.0;
  double volume_m3 = 0.0;
  double youngs_modulus_pa = 0.0;
  double poisson_ratio = 0.0;
  double omega_max_rad_per_s = 0.0;  ///< highest natural frequency at rest [rad/s]
  double stable_step_s = 0.0;        ///< largest step taken in one go [s]
};

/// A scene's world stepped off-line (MuJoCo's mj_step): the model/data pair of the server's
/// world with one command. step() allocates nothing. Body indices are checked by the caller
/// (0 <= body < body_count()).
class World {
 public:
  explicit World(std::shared_ptr<const SceneModel> scene);
  ~World();
  World(World&&) noexcept;
  World& operator=(World&&) noexcept;

  /// The command the slave tracks (world frame [m], [m/s]); kinematic: a tool put there.
  void set_tip(const Eigen::Vector3d& position_m, const Eigen::Vector3d& velocity_mps,
               bool kinematic);
  /// Advances the world `n` physics periods, counting the fault events it raises.
  void step(std::uint64_t n);
  /// Puts the tool at rest at `position_m` [m] (false for a robot scene).
  bool place_tool(const Eigen::Vector3d& position_m);

  /// The tip and its contact after the last step, as the master would have them (world frame):
  /// position, orientation, velocity, contact force, penetration, deformation, in_contact and
  /// sim_time_s; the other fields are left at their defaults.
  SlaveSample readout() const;
  double dt_s() const;           ///< the physics period [s]
  std::uint64_t faults() const;  ///< fault events so far
  std::size_t body_count() const;
  BodyInfo body_info(std::size_t body) const;
  /// Node positions of a deformable body, 3 x N [m].
  const Eigen::Matrix3Xd& nodes(std::size_t body) const;
  /// Rest positions of the same nodes, 3 x N [m].
  const Eigen::Matrix3Xd& rest_nodes(std::size_t body) const;
  /// Surface triangles (node indices), 3 x M.
  const Eigen::Matrix3Xi& triangles(std::size_t body) const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace teleop::harness
