#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "server/node/server_cycle.hpp"
#include "server/world/world_model.hpp"

namespace teleop::server {
namespace {

// A command's K_ps beyond what the tool slave holds at its rate is clamped and counted, and
// the slave then settles instead of ringing.
TEST(ServerCycleGain, AKpsTheSlaveCannotHoldIsClampedCountedAndReported) {
  const sim::WorldModel m =
      sim::load_world_model(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/tool_only.yaml");
  ServerCycle cycle(m, 1e-3, 0.05);
  const double bound = sim::max_position_gain_n_per_m(m, 1000.0);
  EXPECT_DOUBLE_EQ(cycle.max_gain_n_per_m(), bound);
  SlaveCommand c;
  c.position_m = m.tool_start_m + Eigen::Vector3d(0, 0, 1e-4);
  c.position_gain_n_per_m = 0.5 * bound;  // inside: untouched
  sim::EventQueue events;
  std::int64_t t = 0;
  cycle.on_command(c, t, t);
  EXPECT_EQ(cycle.gains_clamped(), 0u);
  c.position_gain_n_per_m = 9.5e5;  // a valid command (<= 1e6) the slave cannot hold at 1 kHz
  double lo = INFINITY, hi = -INFINITY;
  int limit_events = 0;
  sim::SimEvent e;
  for (int i = 0; i < 3000; ++i) {
    t += 1000000;
    ++c.seq;
    cycle.on_command(c, t, t);
    cycle.step(t, events);
    while (events.pop(e)) {
      if (e.kind == sim::EventKind::kLimit) {
        ++limit_events;
        EXPECT_NE(std::string(e.message).find("position_gain_n_per_m"), std::string::npos);
      }
    }
    if (i >= 2800) {
      lo = std::min(lo, cycle.output().tip_position_m.z());
      hi = std::max(hi, cycle.output().tip_position_m.z());
    }
  }
  EXPECT_EQ(cycle.gains_clamped(), 3000u);
  EXPECT_EQ(limit_events, 1);  // once when the clamping began, not every command
  EXPECT_LT(hi - lo, 1e-6);    // settled (unclamped, 9.5e5 N/m rings: world_step_test)
  EXPECT_NEAR(hi, c.position_m.z(), 1e-4);
}

}  // namespace
}  // namespace teleop::server
