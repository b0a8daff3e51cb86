// The in-process slave is the server's cycle: the tool law behind the port, the watchdog, the
// sample the master would decode from SlaveState, no allocation, and any loaded scene.
#include "server/node/world_slave.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "common/dds/teleop_idl.hpp"
#include "server/node/state_message.hpp"
#include "server/world/world_model.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/support/master_helpers.hpp"

namespace teleop::server {
namespace {

using Eigen::Vector3d;

/// A command of a slow press into the wall at z = 0.5 (tool radius 0.05 m).
SlaveCommand press_command(int i) {
  SlaveCommand c;
  c.seq = static_cast<std::uint64_t>(i + 1);
  c.send_time_s = 1e-3 * i;
  c.position_m = Vector3d(0.01 * std::sin(0.003 * i), 0.0, 0.6 - 1e-4 * i);
  c.velocity_mps = Vector3d(0.0, 0.0, -0.1);
  return c;
}

TEST(WorldSlave, OnAToolWorldItIsTheToolLawExactly) {
  const sim::ToolModel tool = test::wall_tool();
  WorldSlave mine(sim::tool_world_model(tool, Vector3d(0, 0, 0.6)));
  sim::ToolState ts = sim::tool_state_at(Vector3d(0, 0, 0.6));
  for (int i = 0; i < 2000; ++i) {
    const SlaveCommand c = press_command(i);
    sim::ToolInput in;
    in.target_position_m = c.position_m;
    in.target_velocity_mps = c.velocity_mps;
    mine.step(c, 1e-3);
    sim::tool_step(tool, ts, in, 1e-3);
    ASSERT_EQ(mine.sample().position_m, ts.position_m) << i;
    ASSERT_EQ(mine.sample().contact_force_n, ts.contact_force_n) << i;
  }
  EXPECT_TRUE(mine.sample().in_contact);
  EXPECT_EQ(mine.sample().seq, 2000u);
  EXPECT_EQ(mine.sample().command_seq, 2000u);
  // the world's contact events are counted, not lost: it touches the wall and stays on it
  EXPECT_GE(mine.events_of(sim::EventKind::kContactBegin), 1u);
  EXPECT_EQ(mine.events_of(sim::EventKind::kContactBegin),
            mine.events_of(sim::EventKind::kContactEnd) + 1);
  EXPECT_EQ(mine.cycle().watchdog_trips(), 0u);
}

TEST(WorldSlave, HoldsLikeTheServerWhenCommandsStopArriving) {
  WorldSlave slave(sim::tool_world_model(sim::ToolModel{}, Vector3d(0, 0, 0.6)), 1e-3, 0.05);
  SlaveCommand c = press_command(0);
  for (int i = 0; i < 100; ++i) slave.step(c = press_command(i), 1e-3);
  EXPECT_FALSE(slave.cycle().held());
  // the same command again and again is no new arrival: after 50 ms the watchdog holds
  for (int i = 0; i < 49; ++i) slave.step(c, 1e-3);
  EXPECT_FALSE(slave.cycle().held());
  for (int i = 0; i < 10; ++i) slave.step(c, 1e-3);
  EXPECT_TRUE(slave.cycle().held());
  EXPECT_EQ(slave.cycle().watchdog_trips(), 1u);
  // as on the server: "tracking" when the first command came, then "holding"
  EXPECT_EQ(slave.events_of(sim::EventKind::kWatchdog), 2u);
  const Vector3d held_at = slave.sample().position_m;
  for (int i = 0; i < 200; ++i) slave.step(c, 1e-3);
  EXPECT_LT((slave.sample().position_m - held_at).norm(), 1e-3);
  // a new command resumes tracking (and says so)
  slave.step(press_command(101), 1e-3);
  EXPECT_FALSE(slave.cycle().held());
  EXPECT_EQ(slave.events_of(sim::EventKind::kWatchdog), 3u);
  EXPECT_EQ(slave.cycle().watchdog_trips(), 1u);
  // reset starts a new life: nothing counted, the tool where it is put
  slave.reset(Vector3d(0.1, 0.0, 0.7));
  EXPECT_EQ(slave.events_total(), 0u);
  EXPECT_EQ(slave.sample().position_m, Vector3d(0.1, 0.0, 0.7));
  EXPECT_EQ(slave.cycle().steps(), 0u);
}

TEST(WorldSlave, ItsSampleIsWhatTheMasterDecodesFromSlaveState) {
  WorldSlave slave(sim::tool_world_model(test::wall_tool(), Vector3d(0, 0, 0.6)));
  SlaveState msg;
  for (int i = 0; i < 1500; ++i) {
    const SlaveCommand c = press_command(i);
    slave.step(c, 1e-3);
    if (i % 100 != 99) continue;
    pack_slave_state(slave.cycle(), static_cast<std::uint64_t>(i + 1), OwnerReport{}, 0, msg);
    const SlaveSample wire = from_idl(msg);
    const SlaveSample& mine = slave.sample();
    ASSERT_EQ(mine.seq, wire.seq);
    ASSERT_EQ(mine.command_seq, wire.command_seq);
    ASSERT_NEAR(mine.command_send_time_s, wire.command_send_time_s, 1e-9);
    ASSERT_NEAR(mine.orientation.angularDistance(wire.orientation), 0.0, 1e-12);
    ASSERT_EQ(mine.deformation_m, wire.deformation_m);
    ASSERT_EQ(mine.passivity_dissipated_j, wire.passivity_dissipated_j);
    ASSERT_EQ(mine.position_m, wire.position_m);
    ASSERT_EQ(mine.velocity_mps, wire.velocity_mps);
    ASSERT_EQ(mine.contact_force_n, wire.contact_force_n);
    ASSERT_EQ(mine.penetration_m, wire.penetration_m);
    ASSERT_EQ(mine.in_contact, wire.in_contact);
    ASSERT_EQ(mine.sim_time_s, wire.sim_time_s);
    ASSERT_EQ(mine.passivity_session, wire.passivity_session);
    ASSERT_EQ(mine.model.valid, wire.model.valid);
    ASSERT_EQ(mine.model.offset_m, wire.model.offset_m);
    ASSERT_EQ(mine.valid, wire.valid);
  }
  EXPECT_TRUE(slave.sample().in_contact);
}

TEST(WorldSlave, StepAllocatesNothing) {
  WorldSlave slave(sim::tool_world_model(test::wall_tool(), Vector3d(0, 0, 0.6)));
  slave.step(press_command(0), 1e-3);
  test::NoAllocScope no_alloc;
  for (int i = 1; i < 2000; ++i) slave.step(press_command(i), 1e-3);
  EXPECT_EQ(no_alloc.allocations(), 0u);
}

TEST(WorldSlave, RunsTheDefaultSceneRobotAndSphere) {
  // the scene teleop_server loads by default (robot + FEM ball, settled at load: its top sags
  // from 0.5 m to about 0.476 m), stepped in-process: the tip goes down 20 mm past the ball's
  // unloaded top and dents it
  const sim::WorldModel model =
      sim::load_world_model(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/default.yaml");
  ASSERT_TRUE(model.has_robot());
  ASSERT_EQ(model.bodies.size(), 1u);
  WorldSlave slave(model, 1.0 / model.physics_rate_hz);
  const Vector3d home = slave.sample().position_m;
  const Vector3d top(0.6, 0.0, 0.476 + model.tip_radius_m());
  double deepest = 0.0;
  bool touched = false;
  for (int i = 0; i < 2500; ++i) {
    const double a = std::min(1.0, i / 1500.0);
    SlaveCommand c;
    c.seq = static_cast<std::uint64_t>(i + 1);
    c.position_m = home + a * (top - Vector3d(0, 0, 0.02) - home);
    slave.step(c, 1.0 / model.physics_rate_hz);
    touched |= slave.sample().in_contact;
    deepest = std::max(deepest, slave.sample().deformation_m);
  }
  EXPECT_TRUE(touched);
  EXPECT_GT(deepest, 2e-3);
  EXPECT_GT(slave.events_of(sim::EventKind::kContactBegin), 0u);
  EXPECT_EQ(slave.events_of(sim::EventKind::kFault), 0u);
  EXPECT_EQ(slave.cycle().watchdog_trips(), 0u);
}

}  // namespace
}  // namespace teleop::server
