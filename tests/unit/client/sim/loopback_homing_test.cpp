// LoopbackSession with homing (what the campaigns' world runs use): the slave starts where it
// is, the cycle brings it to the mapped device position first, and the session's length and its
// metrics count from the end of homing, as in teleop_master against a live server.
#include <gtest/gtest.h>

#include "client/device/simulated_device.hpp"
#include "client/sim/loopback_session.hpp"
#include "server/node/world_slave.hpp"
#include "server/world/world_model.hpp"

namespace teleop::master {
namespace {

using Eigen::Vector3d;

struct Outcome {
  Vector3d start_m, end_m;
  double time_s = 0.0, session_start_s = 0.0;
  std::uint64_t samples = 0;
  bool homing_after = true;
};

Outcome run(double homing_s) {
  SimulatedDeviceParams dp;
  dp.script.kind = ScriptKind::kHold;  // the hand holds the handle at the device origin
  SimulatedDevice device(dp);
  server::WorldSlave slave(sim::tool_world_model(sim::ToolModel{}, Vector3d(0.3, 0.0, 0.5)), 1e-3);
  LoopbackConfig cfg;
  cfg.controller.scheme = "position-position";
  cfg.controller.workspace.offset_m = Vector3d(0.0, 0.0, 0.6);
  cfg.duration_s = 1.0;
  cfg.homing_s = homing_s;
  LoopbackSession session(cfg, device, slave);
  session.start();
  Outcome r;
  r.start_m = slave.sample().position_m;
  while (session.step()) {
  }
  r.end_m = slave.sample().position_m;
  r.time_s = session.time_s();
  r.session_start_s = session.cycle().session_start_s();
  r.samples = session.metrics().samples();
  r.homing_after = session.cycle().homing();
  return r;
}

TEST(LoopbackSession, WithHomingTheSlaveIsBroughtToTheMappedPointFirst) {
  const Outcome h = run(0.5);
  EXPECT_EQ(h.start_m, Vector3d(0.3, 0.0, 0.5));  // not moved at start
  EXPECT_FALSE(h.homing_after);
  EXPECT_GE(h.session_start_s, 0.5 - 1e-9);  // the path takes homing_s at least
  EXPECT_LT(h.session_start_s, 3.6);         // and ends by its timeout at the latest
  // the session runs duration_s after homing, and only its cycles enter the metrics
  EXPECT_NEAR(h.time_s, h.session_start_s + 1.0, 1.5e-3);
  EXPECT_NEAR(static_cast<double>(h.samples), 1000.0, 2.0);
  EXPECT_LT((h.end_m - Vector3d(0.0, 0.0, 0.6)).norm(), 5e-3);
}

TEST(LoopbackSession, WithoutHomingTheSlaveStartsAtTheMappedPoint) {
  const Outcome n = run(0.0);
  EXPECT_EQ(n.start_m, Vector3d(0.0, 0.0, 0.6));
  EXPECT_NEAR(n.time_s, 1.0, 1.5e-3);
  EXPECT_EQ(n.session_start_s, 0.0);
}

}  // namespace
}  // namespace teleop::master
