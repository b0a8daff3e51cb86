// The server's side of common/harness/in_process.hpp: its scenes are the world models of
// server/world, its slaves server::WorldSlave, its World the model/data pair stepped by
// world_step. Linked (target teleop::world_harness) only into the programs that run both halves.
#include "common/harness/in_process.hpp"

#include <utility>

#include "server/node/scene_objects.hpp"
#include "server/node/world_slave.hpp"
#include "server/world/world.hpp"
#include "server/world/world_model.hpp"

namespace teleop::harness {

struct SceneModel {
  sim::WorldModel world;
};

std::shared_ptr<const SceneModel> load_scene_model(const std::string& file) {
  return std::make_shared<const SceneModel>(SceneModel{sim::load_world_model(file)});
}

const std::string& scene_file(const SceneModel& scene) { return scene.world.file; }
const std::string& scene_name(const SceneModel& scene) { return scene.world.name; }
double scene_physics_rate_hz(const SceneModel& scene) { return scene.world.physics_rate_hz; }

SceneDescription describe_scene(const SceneModel& scene) {
  const sim::WorldData data = sim::make_world_data(scene.world);
  return server::describe_scene(scene.world, data, scene.world.physics_rate_hz);
}

std::unique_ptr<InProcessSlave> make_world_slave(const SceneModel& scene, double dt_s) {
  return std::make_unique<server::WorldSlave>(scene.world, dt_s);
}

std::unique_ptr<InProcessSlave> make_tool_slave(const sim::ToolModel& tool,
                                                const Eigen::Vector3d& start_m, double dt_s) {
  return std::make_unique<server::WorldSlave>(sim::tool_world_model(tool, start_m, 1.0 / dt_s),
                                              dt_s);
}

struct World::State {
  explicit State(std::shared_ptr<const SceneModel> s)
      : scene(std::move(s)),
        data(sim::make_world_data(scene->world)),
        dt_s(1.0 / scene->world.physics_rate_hz) {
    command.position_m = data.out.tip_position_m;
  }

  std::shared_ptr<const SceneModel> scene;
  sim::WorldData data;
  sim::WorldCommand command;
  sim::EventQueue events;
  double dt_s;
  std::uint64_t faults = 0;
};

World::World(std::shared_ptr<const SceneModel> scene)
    : state_(std::make_unique<State>(std::move(scene))) {}
World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

void World::set_tip(const Eigen::Vector3d& position_m, const Eigen::Vector3d& velocity_mps,
                    bool kinematic) {
  state_->command.position_m = position_m;
  state_->command.velocity_mps = velocity_mps;
  state_->command.kinematic = kinematic;
}

void World::step(std::uint64_t n) {
  State& s = *state_;
  for (std::uint64_t i = 0; i < n; ++i) {
    sim::world_step(s.scene->world, s.data, s.command, s.dt_s, s.events);
    sim::SimEvent e;
    while (s.events.pop(e)) {
      if (e.kind == sim::EventKind::kFault) ++s.faults;
    }
  }
}

bool World::place_tool(const Eigen::Vector3d& position_m) {
  state_->command.position_m = position_m;
  return sim::place_tool(state_->scene->world, state_->data, position_m);
}

SlaveSample World::readout() const {
  SlaveSample s;
  server::copy_tip_state(state_->data.out, s);
  return s;
}

double World::dt_s() const { return state_->dt_s; }
std::uint64_t World::faults() const { return state_->faults; }
std::size_t World::body_count() const { return state_->data.bodies.size(); }

BodyInfo World::body_info(std::size_t body) const {
  const sim::deformable::DeformableModel& b = state_->scene->world.bodies.at(body).body;
  return BodyInfo{.model = sim::deformable::to_string(b.params.model),
                  .surface_node_count = b.node_count,
                  .node_count = b.state_node_count(),
                  .triangle_count = b.mesh.triangle_count(),
                  .total_mass_kg = b.total_mass_kg,
                  .volume_m3 = b.volume_m3,
                  .youngs_modulus_pa = b.params.youngs_modulus_pa,
                  .poisson_ratio = b.params.poisson_ratio,
                  .omega_max_rad_per_s = b.omega_max_rad_per_s,
                  .stable_step_s = b.stable_step_s};
}

const Eigen::Matrix3Xd& World::nodes(std::size_t body) const {
  return state_->data.bodies.at(body).state.x;
}

const Eigen::Matrix3Xd& World::rest_nodes(std::size_t body) const {
  const sim::deformable::DeformableModel& b = state_->scene->world.bodies.at(body).body;
  return b.params.model == sim::deformable::ModelKind::kFem ? b.fem.rest : b.mesh.vertices;
}

const Eigen::Matrix3Xi& World::triangles(std::size_t body) const {
  return state_->scene->world.bodies.at(body).body.mesh.triangles;
}

}  // namespace teleop::harness
