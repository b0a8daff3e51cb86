// The server's binding of common/harness/in_process.hpp: its slaves are the server's WorldSlave
// on the same worlds, its scene description the server's, and its World the model/data pair
// stepped by world_step, allocation-free.
#include "common/harness/in_process.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "server/node/scene_objects.hpp"
#include "server/node/world_slave.hpp"
#include "server/world/world.hpp"
#include "server/world/world_model.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/support/master_helpers.hpp"

namespace teleop::harness {
namespace {

using Eigen::Vector3d;

const std::string kScene = std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/paper_sphere.yaml";

/// A slow press downwards from `start_m`, one command per step.
SlaveCommand press_command(const Vector3d& start_m, int i) {
  SlaveCommand c;
  c.seq = static_cast<std::uint64_t>(i + 1);
  c.send_time_s = 1e-3 * i;
  c.position_m = start_m + Vector3d(0.01 * std::sin(0.003 * i), 0.0, -1e-4 * i);
  c.velocity_mps = Vector3d(0.0, 0.0, -0.1);
  return c;
}

/// Steps `mine` and `server` with the same commands; their samples agree bit for bit.
void expect_same_steps(SlaveSimulator& mine, server::WorldSlave& server, int steps, double dt_s) {
  const Vector3d start = server.sample().position_m;
  for (int i = 0; i < steps; ++i) {
    const SlaveCommand c = press_command(start, i);
    mine.step(c, dt_s);
    server.step(c, dt_s);
    ASSERT_EQ(mine.sample().position_m, server.sample().position_m) << i;
    ASSERT_EQ(mine.sample().contact_force_n, server.sample().contact_force_n) << i;
    ASSERT_EQ(mine.sample().seq, server.sample().seq) << i;
  }
}

TEST(InProcess, AToolSlaveIsTheServersWorldSlaveOnTheToolWorld) {
  const sim::ToolModel tool = test::wall_tool();
  const Vector3d start(0.0, 0.0, 0.6);
  const std::unique_ptr<InProcessSlave> mine = make_tool_slave(tool, start, 1e-3);
  server::WorldSlave server(sim::tool_world_model(tool, start, 1000.0), 1e-3);
  ASSERT_NO_FATAL_FAILURE(expect_same_steps(*mine, server, 2000, 1e-3));
  EXPECT_TRUE(mine->sample().in_contact);
  EXPECT_EQ(mine->events_of(sim::EventKind::kContactBegin),
            server.events_of(sim::EventKind::kContactBegin));
  EXPECT_GE(mine->events_of(sim::EventKind::kContactBegin), 1u);
  EXPECT_EQ(mine->watchdog_trips(), server.cycle().watchdog_trips());
}

TEST(InProcess, ASceneSlaveIsTheServersWorldSlaveOnTheLoadedScene) {
  const std::shared_ptr<const SceneModel> scene = load_scene_model(kScene);
  EXPECT_EQ(scene_file(*scene), kScene);
  EXPECT_EQ(scene_name(*scene), "paper_sphere");
  const double dt = 1.0 / scene_physics_rate_hz(*scene);
  const std::unique_ptr<InProcessSlave> mine = make_world_slave(*scene, dt);
  server::WorldSlave server(sim::load_world_model(kScene), dt);
  EXPECT_EQ(mine->describe_scene(), server::describe_scene(server.model(), server.cycle().data(),
                                                           server.model().physics_rate_hz));
  EXPECT_EQ(describe_scene(*scene), mine->describe_scene());
  ASSERT_NO_FATAL_FAILURE(expect_same_steps(*mine, server, 300, dt));
  EXPECT_EQ(mine->events_of(sim::EventKind::kFault), 0u);
}

TEST(InProcess, TheWorldIsWorldStepOnTheSceneAndAllocatesNothing) {
  const std::shared_ptr<const SceneModel> scene = load_scene_model(kScene);
  World world(scene);
  const sim::WorldModel model = sim::load_world_model(kScene);
  sim::WorldData data = sim::make_world_data(model);
  ASSERT_EQ(world.body_count(), 1u);
  ASSERT_EQ(world.nodes(0), data.bodies[0].state.x);
  EXPECT_EQ(world.rest_nodes(0), model.bodies[0].body.mesh.vertices);
  EXPECT_EQ(world.triangles(0), model.bodies[0].body.mesh.triangles);
  const BodyInfo info = world.body_info(0);
  EXPECT_EQ(info.node_count, model.bodies[0].body.state_node_count());
  EXPECT_EQ(info.triangle_count, model.bodies[0].body.mesh.triangle_count());
  EXPECT_EQ(info.total_mass_kg, model.bodies[0].body.total_mass_kg);

  sim::WorldCommand cmd;
  cmd.position_m = data.out.tip_position_m + Vector3d(0.0, 0.0, -0.05);
  cmd.velocity_mps = Vector3d(0.0, 0.0, -0.05);
  world.set_tip(cmd.position_m, cmd.velocity_mps, false);
  sim::EventQueue events;
  for (int i = 0; i < 200; ++i) {
    sim::world_step(model, data, cmd, world.dt_s(), events);
    events.clear();
  }
  {
    test::NoAllocScope no_alloc;
    world.step(200);
    EXPECT_EQ(no_alloc.allocations(), 0u);
  }
  const SlaveSample s = world.readout();
  EXPECT_EQ(s.sim_time_s, data.out.sim_time_s);
  EXPECT_EQ(s.position_m, data.out.tip_position_m);
  EXPECT_EQ(s.contact_force_n, data.out.contact_force_n);
  EXPECT_EQ(world.nodes(0), data.bodies[0].state.x);
  EXPECT_EQ(world.faults(), 0u);
  EXPECT_NEAR(s.sim_time_s, 0.2, 1e-9);
}

}  // namespace
}  // namespace teleop::harness
