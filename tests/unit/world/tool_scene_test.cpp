#include "common/sim/tool.hpp"

#include <gtest/gtest.h>

#include "server/world/world.hpp"
#include "tests/support/alloc_counter.hpp"

namespace teleop::sim {
namespace {

ToolModel free_tool() {
  ToolModel m;
  m.gravity_mps2 = Eigen::Vector3d(0, 0, -9.81);
  return m;
}

ToolModel tool_over_floor() {
  ToolModel m = free_tool();
  Plane floor;
  floor.id = 100;
  floor.normal = Eigen::Vector3d::UnitZ();
  floor.offset_m = 0.0;
  floor.stiffness_n_per_m = 2e4;
  floor.damping_ns_per_m = 50;
  m.add(Obstacle::of(floor));
  return m;
}

TEST(ToolScene, TracksACommandedPositionUnderGravity) {
  const ToolModel m = free_tool();
  ToolState s;
  s.position_m = Eigen::Vector3d(0.6, 0.0, 0.7);
  ToolInput in;
  in.target_position_m = Eigen::Vector3d(0.5, 0.1, 0.4);
  for (int i = 0; i < 3000; ++i) tool_step(m, s, in, 1e-3);
  EXPECT_LT((s.position_m - in.target_position_m).norm(), 1e-3);
  EXPECT_LT(s.velocity_mps.norm(), 1e-3);
}

TEST(ToolScene, FloorContactForceBalancesThePdPush) {
  const ToolModel m = tool_over_floor();
  ToolState s;
  s.position_m = Eigen::Vector3d(0.6, 0.0, 0.3);
  ToolInput in;
  in.target_position_m = Eigen::Vector3d(0.6, 0.0, 0.0);  // 50 mm below where the tool rests
  for (int i = 0; i < 5000; ++i) tool_step(m, s, in, 1e-3);
  // at rest: contact + control - m g = 0 (the control force includes gravity compensation)
  const double depth = s.penetration_m;
  EXPECT_GT(depth, 0.0);
  EXPECT_NEAR(s.contact_force_n.z(), m.obstacles[0].stiffness_n_per_m * depth, 1e-6);
  EXPECT_NEAR(s.contact_force_n.z(), -s.control_force_n.z() + m.mass_kg * 9.81, 0.05);
  EXPECT_EQ(s.contact_object, 100);
  // the tool stays on the floor surface within the penalty depth
  EXPECT_NEAR(s.position_m.z(), m.radius_m - depth, 1e-9);
}

TEST(ToolScene, HoldLatchesThePositionAndIgnoresTargets) {
  const ToolModel m = free_tool();
  ToolState s;
  s.position_m = Eigen::Vector3d(0.2, 0.2, 0.2);
  ToolInput in;
  in.hold = true;
  in.target_position_m = Eigen::Vector3d(1, 1, 1);
  for (int i = 0; i < 2000; ++i) tool_step(m, s, in, 1e-3);
  EXPECT_LT((s.position_m - Eigen::Vector3d(0.2, 0.2, 0.2)).norm(), 1e-3);
}

TEST(ToolScene, RotatesTowardTheCommandedOrientation) {
  const ToolModel m = free_tool();
  ToolState s;
  ToolInput in;
  in.target_orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()));
  for (int i = 0; i < 5000; ++i) tool_step(m, s, in, 1e-3);
  EXPECT_LT(s.orientation.angularDistance(in.target_orientation), 1e-3);
}

TEST(ToolScene, StepIsDeterministicAndAllocationFree) {
  const ToolModel m = tool_over_floor();
  ToolState a, b;
  a.position_m = b.position_m = Eigen::Vector3d(0.6, 0, 0.3);
  ToolInput in;
  in.target_position_m = Eigen::Vector3d(0.6, 0, 0.01);
  teleop::test::NoAllocScope scope;
  for (int i = 0; i < 1000; ++i) {
    tool_step(m, a, in, 1e-3);
    tool_step(m, b, in, 1e-3);
  }
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(a.position_m, b.position_m);
  EXPECT_EQ(a.velocity_mps, b.velocity_mps);
}

TEST(WorldStepToolOnly, NonFiniteCommandIsReportedAndTheStateStaysFinite) {
  WorldModel model;
  model.tool = tool_over_floor();
  WorldData world = make_world_data(model);
  EventQueue events;
  WorldCommand cmd;
  cmd.position_m = Eigen::Vector3d(std::nan(""), 0, 0);
  world_step(model, world, cmd, 1e-3, events);
  EXPECT_TRUE(world.out.tip_position_m.allFinite());
  SimEvent e;
  bool fault = false;
  while (events.pop(e)) fault |= e.kind == EventKind::kFault;
  EXPECT_TRUE(fault);
}

TEST(WorldStepToolOnly, ReportsContactBeginAndEnd) {
  WorldModel model;
  model.tool = tool_over_floor();
  model.tool_start_m = Eigen::Vector3d(0.6, 0, 0.2);
  WorldData world = make_world_data(model);
  EventQueue events;
  WorldCommand cmd;
  cmd.position_m = Eigen::Vector3d(0.6, 0, 0.0);
  for (int i = 0; i < 2000; ++i) world_step(model, world, cmd, 1e-3, events);
  EXPECT_TRUE(world.out.in_contact);
  cmd.position_m = Eigen::Vector3d(0.6, 0, 0.3);
  for (int i = 0; i < 2000; ++i) world_step(model, world, cmd, 1e-3, events);
  EXPECT_FALSE(world.out.in_contact);
  int begins = 0, ends = 0;
  SimEvent e;
  while (events.pop(e)) {
    begins += e.kind == EventKind::kContactBegin;
    ends += e.kind == EventKind::kContactEnd;
  }
  EXPECT_GE(begins, 1);
  EXPECT_EQ(begins, ends);
}

TEST(EventQueue, DropsTheOldestWhenFull) {
  EventQueue q;
  for (std::size_t i = 0; i < EventQueue::kCapacity + 5; ++i) {
    q.push(EventKind::kInfo, Severity::kInfo, 0.0, static_cast<double>(i), "x");
  }
  EXPECT_EQ(q.size(), EventQueue::kCapacity);
  EXPECT_EQ(q.dropped(), 5u);
  SimEvent e;
  ASSERT_TRUE(q.pop(e));
  EXPECT_EQ(e.value, 5.0);
}

}  // namespace
}  // namespace teleop::sim
