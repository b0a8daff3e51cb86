#include "common/sim/tool.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include "server/world/world.hpp"
#include "server/world/world_model.hpp"
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

/// Largest swing of the tip's height over the last 200 of 3000 steps with K_ps `kp`, after a
/// 0.1 mm step of the target (the PD stays below its force limit) [m].
double ringing_m(const WorldModel& m, double kp) {
  WorldData d = make_world_data(m);
  EventQueue q;
  SimEvent e;
  WorldCommand cmd;
  cmd.position_m = m.tool_start_m + Eigen::Vector3d(0, 0, 1e-4);
  cmd.kp_override_n_per_m = kp;
  double lo = INFINITY, hi = -INFINITY;
  for (int i = 0; i < 3000; ++i) {
    world_step(m, d, cmd, 1e-3, q);
    while (q.pop(e)) {
    }
    if (i >= 2800) {
      lo = std::min(lo, d.out.tip_position_m.z());
      hi = std::max(hi, d.out.tip_position_m.z());
    }
  }
  return std::isfinite(hi - lo) ? hi - lo : std::numeric_limits<double>::infinity();
}

TEST(ToolScene, TheLargestKpsFollowsTheStableStepAndHolds) {
  const WorldModel m =
      load_world_model(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/tool_only.yaml");
  const double bound = max_position_gain_n_per_m(m, 1000.0);
  // on the floor: h^2 (kp + k_c) / m + 2 h (c + c_c) / m <= 4 with h = dt / 0.95, m 0.2 kg,
  // c 12 + 0.5 N s/m, k_c 2e4 N/m, c_c 50 N s/m (below the free limit, c_c = k_c = 0)
  const double h = 1e-3 / kRateSafety;
  EXPECT_NEAR(bound, (4.0 * 0.2 - 2.0 * h * 62.5) / (h * h) - 2e4, 1.0);
  EXPECT_LT(bound, (4.0 * 0.2 - 2.0 * h * 12.5) / (h * h));
  EXPECT_GT(bound, m.tool.kp_n_per_m);
  EXPECT_LT(bound, kMaxPositionGainNPerM);
  // the bound grows with the rate (the same limit at h = 1 / (1100 Hz x 0.95)), up to the
  // wire's 1e6; a robot slave does not use K_ps
  const double h11 = 1.0 / (1100.0 * kRateSafety);
  EXPECT_NEAR(max_position_gain_n_per_m(m, 1100.0),
              (4.0 * 0.2 - 2.0 * h11 * 62.5) / (h11 * h11) - 2e4, 1.0);
  EXPECT_EQ(max_position_gain_n_per_m(m, 2000.0), kMaxPositionGainNPerM);
  WorldModel robot = m;
  robot.slave = SlaveKind::kRobot;
  EXPECT_EQ(max_position_gain_n_per_m(robot, 1000.0), kMaxPositionGainNPerM);
  // at the bound the tip settles; at 1.2 times the limit without the safety factor it rings
  EXPECT_LT(ringing_m(m, bound), 1e-6);
  const double unsafe = 1.2 * (4.0 * 0.2 - 2.0 * 1e-3 * 12.5) / 1e-6;
  EXPECT_LT(unsafe, kMaxPositionGainNPerM);  // a command may carry it: the server clamps it
  EXPECT_GT(ringing_m(m, unsafe), 1e-5);
}

/// Peak-to-peak of the floor's force on the tool over the last 500 of 3000 steps with K_ps
/// `kp`, its target coming down at 0.5 m/s to 2 mm below the surface (below the PD's force
/// limit) and holding there, relative to the force's mean there.
double contact_ringing(const WorldModel& m, double kp) {
  WorldData d = make_world_data(m);
  EventQueue q;
  SimEvent e;
  WorldCommand cmd;
  cmd.kp_override_n_per_m = kp;
  const double bottom_m = m.tool.radius_m - 2e-3;
  double lo = INFINITY, hi = -INFINITY, sum = 0.0;
  for (int i = 0; i < 3000; ++i) {
    const double z = m.tool_start_m.z() - 0.5e-3 * (i + 1);
    cmd.position_m = m.tool_start_m;
    cmd.position_m.z() = std::max(z, bottom_m);
    cmd.velocity_mps = Eigen::Vector3d(0, 0, z > bottom_m ? -0.5 : 0.0);
    world_step(m, d, cmd, 1e-3, q);
    while (q.pop(e)) {
    }
    if (i >= 2500) {
      lo = std::min(lo, d.out.contact_force_n.z());
      hi = std::max(hi, d.out.contact_force_n.z());
      sum += d.out.contact_force_n.z();
    }
  }
  return (hi - lo) / (sum / 500.0);
}

// In contact the explicit step applies the floor's damper as well as its spring: the tool's PD
// on tool_only.yaml's floor is stable up to h^2 (kp + k_c) / m + 2 h (c + c_c) / m = 4 at
// h = 1 ms (655000 N/m), not up to h^2 (kp + k_c) / m = 4 (780000 N/m): 3 % below it the force
// settles, 3 % above it rings between zero and the PD's force limit.
TEST(ToolScene, InContactTheStableStepCountsTheContactDamper) {
  const WorldModel m =
      load_world_model(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/tool_only.yaml");
  const double limit = (4.0 * 0.2 - 2.0 * 1e-3 * 62.5) / 1e-6 - 2e4;
  EXPECT_LT(contact_ringing(m, 0.97 * limit), 1e-6);
  EXPECT_GT(contact_ringing(m, 1.03 * limit), 1.0);
  EXPECT_LT(max_position_gain_n_per_m(m, 1000.0), 0.97 * limit);
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

// --- robot and robot + sphere: the default scene through world_step --------------------------

WorldModel default_scene() {
  return load_world_model(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/default.yaml");
}

/// The paper's scene: the robot over the surface mass-spring sphere.
WorldModel paper_scene() {
  return load_world_model(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/paper_sphere.yaml");
}

/// Counts the events of `kind` about object `id` (any object when id < 0) and empties the queue.
struct EventCount {
  int begins = 0, ends = 0, faults = 0;
  void drain(EventQueue& q, int id) {
    SimEvent e;
    while (q.pop(e)) {
      const bool mine = id < 0 || static_cast<int>(e.value) == id;
      begins += mine && e.kind == EventKind::kContactBegin;
      ends += mine && e.kind == EventKind::kContactEnd;
      faults += e.kind == EventKind::kFault;
    }
  }
};

/// Steps towards `to` along a straight line over `ramp_s`, then holds there for `hold_s`.
void move(const WorldModel& m, WorldData& d, EventQueue& q, EventCount& c, int id,
          const Eigen::Vector3d& to, double ramp_s, double hold_s) {
  const Eigen::Vector3d from = d.out.tip_position_m;
  const int ramp = static_cast<int>(ramp_s * 1000), hold = static_cast<int>(hold_s * 1000);
  WorldCommand cmd;
  for (int i = 1; i <= ramp + hold; ++i) {
    const double s = std::min(1.0, static_cast<double>(i) / std::max(1, ramp));
    cmd.position_m = from + s * (to - from);
    world_step(m, d, cmd, 1e-3, q);
    c.drain(q, id);
  }
}

int plane_id(const WorldModel& m, const std::string& name) {
  for (const Plane& p : m.planes) {
    if (p.name == name) return p.id;
  }
  return -1;
}

TEST(WorldStepRobot, TouchesTheFloorWithContactEventsAndStaysFinite) {
  WorldModel model = default_scene();
  model.bodies.clear();  // the robot alone over its floor and wall
  ASSERT_TRUE(model.has_robot());
  WorldData world = make_world_data(model);
  EXPECT_EQ(world.out.joint_count, 6);
  EventQueue events;
  EventCount floor;
  const int floor_id = plane_id(model, "floor");
  ASSERT_GE(floor_id, 0);
  // away from where the sphere was, down onto the floor (tip radius 0.05 m), then back up
  move(model, world, events, floor, floor_id, Eigen::Vector3d(0.35, 0.3, 0.3), 1.5, 0.5);
  EXPECT_EQ(floor.begins, 0);
  move(model, world, events, floor, floor_id, Eigen::Vector3d(0.35, 0.3, 0.03), 1.0, 0.5);
  EXPECT_TRUE(world.out.in_contact);
  EXPECT_EQ(world.out.contact_object, floor_id);
  EXPECT_GT(world.out.contact_force_n.z(), 0.0);  // the floor pushes up
  EXPECT_EQ(floor.begins, 1);  // one event per contact (the world's; the robot emits none)
  EXPECT_EQ(floor.ends, 0);
  move(model, world, events, floor, floor_id, Eigen::Vector3d(0.35, 0.3, 0.3), 1.0, 0.5);
  EXPECT_FALSE(world.out.in_contact);
  EXPECT_EQ(floor.ends, 1);
  EXPECT_EQ(floor.faults, 0);
  EXPECT_NEAR((world.out.tip_position_m - Eigen::Vector3d(0.35, 0.3, 0.3)).norm(), 0.0, 0.01);
}

TEST(WorldStepRobot, NonFiniteCommandIsAFaultNotAJump) {
  WorldModel model = default_scene();
  model.bodies.clear();
  WorldData world = make_world_data(model);
  EventQueue events;
  const Eigen::Vector3d before = world.out.tip_position_m;
  WorldCommand cmd;
  cmd.position_m = Eigen::Vector3d(std::nan(""), 0.0, 0.5);
  EventCount c;
  for (int i = 0; i < 50; ++i) {
    world_step(model, world, cmd, 1e-3, events);
    c.drain(events, -1);
  }
  EXPECT_GE(c.faults, 1);
  EXPECT_TRUE(world.out.tip_position_m.allFinite());
  EXPECT_LT((world.out.tip_position_m - before).norm(), 0.01);  // held, not thrown
}

// The default scene's FEM ball and the paper's mass-spring sphere alike.
TEST(WorldStepRobotSphere, SphereSleepsAwayFromTheTipAndWakesOnContact) {
  for (const WorldModel& model : {default_scene(), paper_scene()}) {
    SCOPED_TRACE(model.name);
    ASSERT_EQ(model.bodies.size(), 1u);
    const int sphere = model.bodies[0].object_id;
    WorldData world = make_world_data(model);
    EventQueue events;
    EventCount c;
    const double top = world.bodies[0].state.x.row(2).maxCoeff();  // as loaded (settled or not)
    // the tip stays 0.2 m above the sphere's top: the body settles on the floor and sleeps
    // (it settles in about 3.5 s from its rest shape under gravity)
    const Eigen::Vector3d centroid = world.bodies[0].state.x.rowwise().mean();
    move(model, world, events, c, sphere, Eigen::Vector3d(0.6, 0.0, 0.75), 0.5, 5.0);
    EXPECT_TRUE(world.bodies[0].state.sleeping);
    // at rest where it was put: a body sags straight down, it does not roll off its contact
    EXPECT_LT((world.bodies[0].state.x.rowwise().mean() - centroid).head<2>().norm(), 2e-4);
    const std::uint64_t asleep = world.bodies[0].state.sleeping_steps;
    move(model, world, events, c, sphere, Eigen::Vector3d(0.6, 0.0, 0.75), 0.0, 0.1);
    EXPECT_EQ(world.bodies[0].state.sleeping_steps, asleep + 100);  // skipped, not integrated
    EXPECT_EQ(c.begins, 0);
    // 20 mm down into the top (tip radius 0.05): contact begins, the body wakes and pushes
    move(model, world, events, c, sphere, Eigen::Vector3d(0.6, 0.0, top + 0.05 - 0.02), 1.0, 0.5);
    EXPECT_TRUE(world.out.in_contact);
    EXPECT_EQ(world.out.contact_object, sphere);
    EXPECT_FALSE(world.bodies[0].state.sleeping);
    EXPECT_GT(world.out.contact_force_n.z(), 0.0);
    EXPECT_GT(world.out.deformation_m, 0.0);
    EXPECT_EQ(c.begins, 1);
    // and up again: one end event, no fault
    move(model, world, events, c, sphere, Eigen::Vector3d(0.6, 0.0, 0.75), 1.0, 0.5);
    EXPECT_FALSE(world.out.in_contact);
    EXPECT_EQ(c.ends, 1);
    EXPECT_EQ(c.faults, 0);
  }
}

TEST(WorldStepRobotSphere, ABodyThatBlowsUpIsResetAndReportedNotPropagated) {
  const WorldModel model = default_scene();
  WorldData world = make_world_data(model);
  EventQueue events;
  EventCount c;
  move(model, world, events, c, -1, Eigen::Vector3d(0.6, 0.0, 0.75), 0.2, 0.1);
  world.bodies[0].state.x(2, 0) = std::nan("");  // a node's state goes bad
  deformable::wake(world.bodies[0].state);
  move(model, world, events, c, -1, Eigen::Vector3d(0.6, 0.0, 0.75), 0.0, 0.2);
  EXPECT_GE(c.faults, 1);
  EXPECT_TRUE(world.bodies[0].state.x.allFinite());
  EXPECT_TRUE(world.out.contact_force_n.allFinite());
  EXPECT_TRUE(world.out.tip_position_m.allFinite());
}

// b reads its data into the caches before each step (world_prewarm, the live loop's prewarm):
// the same bits as a, which does not
TEST(WorldStepRobotSphere, DeterministicAllocationFreeAndUnchangedByAPrewarmThroughAPress) {
  const WorldModel model = default_scene();
  WorldData a = make_world_data(model);
  WorldData b = make_world_data(model);
  EventQueue qa, qb;
  WorldCommand cmd;
  const Eigen::Vector3d from = a.out.tip_position_m;
  const Eigen::Vector3d to(0.6, 0.0, 0.52);
  SimEvent e;
  std::uint64_t allocations = 0, touched = 0;
  for (int i = 1; i <= 2500; ++i) {
    cmd.position_m = from + std::min(1.0, i / 2000.0) * (to - from);
    teleop::test::NoAllocScope scope;
    world_step(model, a, cmd, 1e-3, qa);
    touched += world_prewarm(model, b);
    world_step(model, b, cmd, 1e-3, qb);
    while (qa.pop(e)) {
    }
    while (qb.pop(e)) {
    }
    allocations += scope.allocations();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_TRUE(a.out.in_contact);
  EXPECT_EQ(a.out.tip_position_m, b.out.tip_position_m);
  EXPECT_EQ(a.out.contact_force_n, b.out.contact_force_n);
  EXPECT_EQ(a.bodies[0].state.x, b.bodies[0].state.x);
  EXPECT_EQ(a.bodies[0].state.v, b.bodies[0].state.v);
  EXPECT_EQ(a.out.q_rad, b.out.q_rad);
  EXPECT_EQ(a.out.qd_radps, b.out.qd_radps);
  EXPECT_GT(touched, 0u);  // it read something
}

// --- a kinematic tool (prescribed probe, the contact experiments) -----------------------------

/// The paper scene's mass-spring sphere under a tool (radius 0.05 m) over the floor, the tool
/// 0.1 m above the sphere's top.
WorldModel probe_over_sphere() {
  ToolModel tool = tool_over_floor();
  tool.radius_m = 0.05;
  WorldModel m = tool_world_model(tool, Eigen::Vector3d(0.6, 0.0, 0.65));
  m.bodies = paper_scene().bodies;
  return m;
}

TEST(WorldStepKinematic, TheProbeGoesWhereToldAndFeelsOnlyTheBody) {
  const WorldModel model = probe_over_sphere();
  ASSERT_EQ(model.planes.size(), 1u);
  WorldData world = make_world_data(model);
  EventQueue events;
  EventCount c;
  WorldCommand cmd;
  cmd.kinematic = true;
  cmd.velocity_mps = Eigen::Vector3d(0.0, 0.0, -0.05);
  cmd.position_m = world.out.tip_position_m;
  double deepest_force = 0.0;
  for (int i = 0; i < 2400; ++i) {  // 0.12 m down at 5 cm/s: 2 cm into the top
    cmd.position_m += cmd.velocity_mps * 1e-3;
    world_step(model, world, cmd, 1e-3, events);
    c.drain(events, model.bodies[0].object_id);
    ASSERT_EQ(world.out.tip_position_m, cmd.position_m) << i;  // exactly where it was told
    ASSERT_EQ(world.out.tip_velocity_mps, cmd.velocity_mps);
    // its force is the body's reaction, and its tracking force balances it
    ASSERT_EQ(world.out.contact_force_n, world.deformable_force_n);
    ASSERT_EQ(world.out.tracking_force_n, -world.out.contact_force_n);
    deepest_force = std::max(deepest_force, world.out.contact_force_n.z());
  }
  EXPECT_TRUE(world.out.in_contact);
  EXPECT_EQ(world.out.contact_object, model.bodies[0].object_id);
  EXPECT_GT(deepest_force, 0.5);
  EXPECT_EQ(c.begins, 1);
  EXPECT_EQ(c.faults, 0);
  // the planes do not act on a probe: put it into the floor, far from the sphere
  EXPECT_TRUE(place_tool(model, world, Eigen::Vector3d(-0.6, 0.0, 0.3)));
  cmd.velocity_mps.setZero();
  cmd.position_m = Eigen::Vector3d(-0.6, 0.0, -0.02);
  world_step(model, world, cmd, 1e-3, events);
  EXPECT_EQ(world.out.contact_force_n, Eigen::Vector3d::Zero());
  EXPECT_FALSE(world.out.in_contact);
  // a non-finite probe command leaves it where it is, with a fault
  cmd.position_m.x() = std::nan("");
  world_step(model, world, cmd, 1e-3, events);
  EXPECT_EQ(world.out.tip_position_m, Eigen::Vector3d(-0.6, 0.0, -0.02));
  c.drain(events, -1);
  EXPECT_EQ(c.faults, 1);
}

/// The mean tangential / normal force on a probe that presses 5 mm into the top of the shipped
/// fem ball (default.yaml, settled on the floor) and slides along +x at 20 mm/s, with the tip
/// friction (mu_s, mu_k) of the body's contact block; over the last 0.2 s of 0.4 s of sliding.
double fem_probe_friction_ratio(double mu_s, double mu_k) {
  ToolModel tool = tool_over_floor();
  tool.radius_m = 0.05;
  WorldModel model = tool_world_model(tool, Eigen::Vector3d(0.6, 0.0, 0.6));
  model.bodies =
      load_world_model(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/default.yaml").bodies;
  model.bodies[0].contact.friction_static = mu_s;
  model.bodies[0].contact.friction_kinetic = mu_k;
  WorldData world = make_world_data(model);
  EventQueue events;
  WorldCommand cmd;
  cmd.kinematic = true;
  // down onto the settled top, then 5 mm into it, then along +x
  const double top = world.bodies[0].state.x.row(2).maxCoeff();
  cmd.position_m = Eigen::Vector3d(0.6, 0.0, top + 0.05 + 1e-3);
  double fx = 0.0, fz = 0.0;
  for (int k = 0; k < 700; ++k) {
    cmd.velocity_mps = k < 300 ? Eigen::Vector3d(0.0, 0.0, -0.02) : Eigen::Vector3d(0.02, 0.0, 0.0);
    cmd.position_m += cmd.velocity_mps * 1e-3;
    world_step(model, world, cmd, 1e-3, events);
    if (k >= 500) {
      fx += world.out.contact_force_n.x();
      fz += world.out.contact_force_n.z();
    }
  }
  EXPECT_TRUE(world.out.in_contact);
  return -fx / fz;
}

TEST(WorldStepKinematic, AFemBallTakesTheTipFrictionOfItsContactBlock) {
  const double frictionless = fem_probe_friction_ratio(0.0, 0.0);
  const double sliding = fem_probe_friction_ratio(0.3, 0.24);
  std::printf(
      "fem ball, probe sliding: tangential / normal force %.4f frictionless, %.4f with "
      "mu_s 0.3, mu_k 0.24\n",
      frictionless, sliding);
  // the ball is free on the floor: dragged at its top it rolls along, so the tip mostly sticks
  // and the force stays below mu_k (the slide against a held ball: fem_test.cpp); frictionless,
  // only the tilt of the contact normal remains
  EXPECT_LT(std::fabs(frictionless), 0.03);
  EXPECT_GT(sliding, 5.0 * std::fabs(frictionless));
  EXPECT_GT(sliding, 0.05);
  EXPECT_LT(sliding, 0.3);
}

TEST(WorldStepKinematic, PlaceToolResetsTheContactsAndRobotsRefuse) {
  const WorldModel model = probe_over_sphere();
  WorldData world = make_world_data(model);
  EventQueue events;
  WorldCommand cmd;
  cmd.kinematic = true;
  cmd.position_m = Eigen::Vector3d(0.6, 0.0, 0.53);  // 2 cm into the top
  for (int i = 0; i < 300; ++i) world_step(model, world, cmd, 1e-3, events);
  ASSERT_TRUE(world.bodies[0].contact.in_contact());
  const double t = world.out.sim_time_s;
  EXPECT_TRUE(place_tool(model, world, Eigen::Vector3d(0.6, 0.0, 0.8)));
  EXPECT_FALSE(world.bodies[0].contact.in_contact());
  EXPECT_FALSE(world.bodies[0].last.in_contact);
  EXPECT_EQ(world.out.tip_position_m, Eigen::Vector3d(0.6, 0.0, 0.8));
  EXPECT_EQ(world.tip_prev_m, Eigen::Vector3d(0.6, 0.0, 0.8));
  EXPECT_EQ(world.out.sim_time_s, t);  // no step was taken
  const WorldModel robot = default_scene();
  WorldData rd = make_world_data(robot);
  const Eigen::Vector3d tip = rd.out.tip_position_m;
  EXPECT_FALSE(place_tool(robot, rd, Eigen::Vector3d(0.6, 0.0, 0.8)));
  EXPECT_EQ(rd.out.tip_position_m, tip);
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
