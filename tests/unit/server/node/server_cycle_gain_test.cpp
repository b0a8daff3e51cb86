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
        // what a master matches on: the subject (the server node adds the command's session)
        EXPECT_EQ(e.tags.subject, sim::EventSubject::kPositionGain);
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

/// The tool-only slave pressed 2 mm into its floor (below its PD's force limit) with K_ps
/// `kps` requested: the target comes down at 0.5 m/s with its velocity from the start and
/// holds; 3 s at 1 kHz.
struct PressResult {
  double mean_n = 0.0;          ///< mean normal contact force over the last 0.5 s [N]
  double peak_to_peak_n = 0.0;  ///< its peak-to-peak over the last 0.5 s [N]
  std::uint64_t clamped = 0;    ///< commands whose K_ps the cycle clamped
  double max_gain_n_per_m = 0.0;
};

PressResult press_floor(double kps) {
  const sim::WorldModel m =
      sim::load_world_model(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/tool_only.yaml");
  ServerCycle cycle(m, 1e-3, 0.05);
  const double bottom_m = m.tool.radius_m - 2e-3;  // the floor is z = 0
  const double speed_mps = 0.5;
  SlaveCommand c;
  c.position_gain_n_per_m = kps;
  sim::EventQueue events;
  sim::SimEvent e;
  double lo = INFINITY, hi = -INFINITY, sum = 0.0;
  int n = 0;
  for (int i = 0; i < 3000; ++i) {
    const std::int64_t t = static_cast<std::int64_t>(i + 1) * 1000000;
    const double z = m.tool_start_m.z() - speed_mps * 1e-3 * (i + 1);
    c.position_m = m.tool_start_m;
    c.position_m.z() = std::max(z, bottom_m);
    c.velocity_mps = Eigen::Vector3d(0, 0, z > bottom_m ? -speed_mps : 0.0);
    ++c.seq;
    cycle.on_command(c, t, t);
    cycle.step(t, events);
    while (events.pop(e)) {
    }
    if (i >= 2500) {
      const double f = cycle.output().contact_force_n.z();
      lo = std::min(lo, f);
      hi = std::max(hi, f);
      sum += f;
      ++n;
    }
  }
  return {sum / n, hi - lo, cycle.gains_clamped(), cycle.max_gain_n_per_m()};
}

// The stable step of the tool's PD in contact counts the contact's damper as well as its
// spring: tool_only.yaml's floor (2e4 N/m, 50 N s/m) with the tool (0.2 kg, 12 + 0.5 N s/m)
// holds h^2 (kp + k_c) / m + 2 h (c + c_c) / m <= 4, with h = 1 ms / 0.95.
TEST(ServerCycleGain, TheBoundCountsTheContactDamper) {
  const sim::WorldModel m =
      sim::load_world_model(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/tool_only.yaml");
  const double h = 1e-3 / sim::kRateSafety;
  EXPECT_NEAR(sim::max_position_gain_n_per_m(m, 1000.0),
              (4.0 * 0.2 - 2.0 * h * (12.5 + 50.0)) / (h * h) - 2e4, 1.0);
}

// A K_ps of 1e6 (the most a command may carry) against the floor is clamped, counted, and the
// contact force settles: a stable loop converges to its static balance, so the force's
// peak-to-peak over the last 0.5 s stays under 1 % of its mean (a loop past its stable step
// rings between zero and the PD's force limit, peak-to-peak near 3 times the mean).
TEST(ServerCycleGain, AKpsThatWouldRingInContactIsClampedAndTheForceSettles) {
  const PressResult r = press_floor(1e6);
  EXPECT_GT(r.clamped, 0u);
  EXPECT_GT(r.mean_n, 30.0);  // in contact: about 2e4 N/m x 2 mm
  EXPECT_LT(r.peak_to_peak_n, 0.01 * r.mean_n);
}

// The largest K_ps the cycle allows is taken as it is and holds in contact.
TEST(ServerCycleGain, TheLargestAllowedKpsHoldsInContact) {
  const sim::WorldModel m =
      sim::load_world_model(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/tool_only.yaml");
  const PressResult r = press_floor(sim::max_position_gain_n_per_m(m, 1000.0));
  EXPECT_EQ(r.clamped, 0u);
  EXPECT_GT(r.mean_n, 30.0);
  EXPECT_LT(r.peak_to_peak_n, 0.01 * r.mean_n);
}

}  // namespace
}  // namespace teleop::server
