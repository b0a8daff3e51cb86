// The master cycle on its own, with a scripted link: homing, delivery of due commands, the
// verdict after a safety cut, and no allocation in step()/finish().
#include "client/cycle/master_cycle.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "client/device/external_device.hpp"
#include "client/device/simulated_device.hpp"
#include "tests/support/alloc_counter.hpp"

namespace teleop::master {
namespace {

/// A link whose slave is where the newest command put it (a perfect position servo), with an
/// optional constant contact force; it counts what it was sent.
struct ServoLink final : SlaveLink {
  std::vector<SlaveCommand> sent;
  SlaveSample slave;
  bool have_command = false;
  Eigen::Vector3d contact_force_n = Eigen::Vector3d::Zero();
  explicit ServoLink(const Eigen::Vector3d& tip) {
    slave.valid = true;
    slave.position_m = tip;
    sent.reserve(20000);
  }
  void send(const SlaveCommand& c) override {
    sent.push_back(c);
    have_command = true;
    slave.position_m = c.position_m;
    slave.command_seq = c.seq;
  }
  bool receive(double now_s, SlaveSample& s, double& at_s) override {
    slave.contact_force_n = contact_force_n;
    slave.in_contact = contact_force_n.squaredNorm() > 0.0;
    s = slave;
    at_s = now_s;
    return true;
  }
};

SimulatedDeviceParams holding_device(const Eigen::Vector3d& at) {
  SimulatedDeviceParams p;
  p.script.kind = ScriptKind::kHold;
  p.script.start_m = at;
  return p;
}

MasterCycleConfig config(const std::string& scheme) {
  MasterCycleConfig c;
  c.controller.scheme = scheme;
  c.controller.workspace.offset_m = Eigen::Vector3d(0.6, 0.0, 0.5);
  return c;
}

TEST(MasterCycle, HomesAlongAMinimumJerkPathWithoutForceThenActivates) {
  SimulatedDevice device(holding_device(Eigen::Vector3d::Zero()));
  const Eigen::Vector3d tip(0.4, 0.1, 0.8);  // where the slave is: 0.37 m from the goal
  ServoLink link(tip);
  MasterCycle cycle(config("position-position"), device, link);
  cycle.start_homing(0.0, tip, 1.0);
  ASSERT_TRUE(cycle.homing());
  const Eigen::Vector3d goal(0.6, 0.0, 0.5);  // the device's origin mapped to the slave
  int homing_cycles = 0;
  double max_step_m = 0.0;
  Eigen::Vector3d prev = tip;
  double t = 0.0;
  while (cycle.homing() && t < 5.0) {
    cycle.step(t);
    cycle.finish(t);
    ++homing_cycles;
    EXPECT_EQ(cycle.device_force_n(), Eigen::Vector3d::Zero());
    const Eigen::Vector3d c = link.sent.back().position_m;
    max_step_m = std::max(max_step_m, (c - prev).norm());
    prev = c;
    t += 1e-3;
  }
  EXPECT_FALSE(cycle.homing());
  EXPECT_NEAR(homing_cycles, 1001, 2);  // the path's 1 s, then the slave is there
  EXPECT_LT((link.sent.back().position_m - goal).norm(), 1e-9);
  // minimum jerk: peak speed 1.875 |goal - tip| / T, so no command jumps more than that * dt
  EXPECT_LT(max_step_m, 1.875 * (goal - tip).norm() * 1e-3 * 1.01);
  EXPECT_EQ(cycle.metrics().samples(), 0u);  // homing is not part of the session's figures
  EXPECT_NEAR(cycle.session_start_s(), 1.0, 2e-3);
  cycle.step(t);
  cycle.finish(t);
  EXPECT_EQ(cycle.metrics().samples(), 1u);
}

TEST(MasterCycle, EveryDueVersusNewestDueDelivery) {
  for (ForwardDelivery d : {ForwardDelivery::kEveryDue, ForwardDelivery::kNewestDue}) {
    SimulatedDevice device(holding_device(Eigen::Vector3d::Zero()));
    ServoLink link(Eigen::Vector3d(0.6, 0.0, 0.5));
    MasterCycleConfig c = config("position-position");
    c.delivery = d;
    c.forward.delay_s = 0.005;
    c.forward.jitter_s = 0.004;  // jittered and reordered: several can fall due at once
    c.forward.reorder = true;
    MasterCycle cycle(c, device, link);
    cycle.start(0.0);
    std::size_t most_in_one_cycle = 0;
    for (int i = 0; i < 2000; ++i) {
      const std::size_t before = link.sent.size();
      cycle.step(i * 1e-3);
      cycle.finish(i * 1e-3);
      most_in_one_cycle = std::max(most_in_one_cycle, link.sent.size() - before);
    }
    if (d == ForwardDelivery::kEveryDue) {
      EXPECT_GT(most_in_one_cycle, 1u);
      EXPECT_GE(link.sent.size(), 1980u);  // all but the last few in flight
    } else {
      EXPECT_EQ(most_in_one_cycle, 1u);
      EXPECT_LT(link.sent.size(), 1980u);  // superseded ones never reach the slave
    }
  }
}

TEST(MasterCycle, ASafetyCutMakesTheVerdictUnstable) {
  SimulatedDevice device(holding_device(Eigen::Vector3d::Zero()));
  ServoLink link(Eigen::Vector3d(0.6, 0.0, 0.5));
  link.contact_force_n = Eigen::Vector3d(0.0, 0.0, 200.0);  // far beyond the device's peak
  MasterCycle cycle(config("force-position"), device, link);
  cycle.start(0.0);
  for (int i = 0; i < 2000 && !cycle.safety().cut(); ++i) {
    cycle.step(i * 1e-3);
    cycle.finish(i * 1e-3);
  }
  ASSERT_TRUE(cycle.safety().cut());
  EXPECT_EQ(cycle.metrics().verdict(), Verdict::kUnstable);
  EXPECT_LE(cycle.device_force_n().norm(), device.spec().max_force_n + 1e-9);
}

TEST(MasterCycle, StepAndFinishAllocateNothing) {
  SimulatedDevice device(holding_device(Eigen::Vector3d::Zero()));
  ServoLink link(Eigen::Vector3d(0.6, 0.0, 0.5));
  MasterCycleConfig c = config("tdpa");
  c.forward.delay_s = c.backward.delay_s = 0.02;
  c.forward.jitter_s = 0.002;
  MasterCycle cycle(c, device, link);
  cycle.start_homing(0.0, Eigen::Vector3d(0.5, 0.0, 0.6), 0.2);
  // a live tuning ramp (gains and delays) runs during the measured cycles
  TuningRequestData tune;
  tune.fields = kTuneMasterStiffness | kTuneMasterDamping | kTuneForwardDelay;
  tune.values.master_stiffness_n_per_m = 800.0;
  tune.values.master_damping_ns_per_m = 4.0;
  tune.values.forward_delay_s = 0.05;
  tune.ramp_s = 2.0;
  ASSERT_EQ(cycle.tune(tune, 0.0), "");
  teleop::test::NoAllocScope scope;
  for (int i = 0; i < 3000; ++i) {
    cycle.step(i * 1e-3);
    cycle.finish(i * 1e-3);
  }
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_FALSE(cycle.homing());
}

/// A slave that can restart (a new life starts at `home`, with a new epoch) and whose samples
/// can stop (a link loss); otherwise a position servo like ServoLink, pushing back with a
/// spring when the commanded tip goes below z = `floor_m` (contact).
struct RestartableLink final : SlaveLink {
  SlaveSample slave;
  Eigen::Vector3d home;
  double floor_m = -1.0;
  bool silent = false;
  explicit RestartableLink(const Eigen::Vector3d& tip) : home(tip) {
    slave.valid = true;
    slave.position_m = tip;
  }
  void restart() {
    slave.position_m = home;
    ++slave.slave_epoch;
  }
  void send(const SlaveCommand& c) override {
    if (silent) return;
    slave.position_m = c.enabled ? c.position_m : slave.position_m;
    slave.command_seq = c.seq;
  }
  bool receive(double now_s, SlaveSample& s, double& at_s) override {
    if (silent) return false;
    const double depth = floor_m - slave.position_m.z();
    slave.in_contact = depth > 0.0;
    slave.contact_force_n = Eigen::Vector3d(0.0, 0.0, depth > 0.0 ? 100.0 * depth : 0.0);
    s = slave;
    at_s = now_s;
    return true;
  }
};

TEST(MasterCycle, ASlaveRestartReHomesWithoutAForceStep) {
  // the device holds 1 cm below the contact plane: force-position renders the slave's 1 N; the
  // slave restarts 0.2 m away; the force must go to zero and come back within the rate bound
  SimulatedDevice device(holding_device(Eigen::Vector3d(0.0, 0.0, -0.01)));
  const Eigen::Vector3d contact(0.6, 0.0, 0.5), home(0.6, 0.0, 0.7);
  RestartableLink link(contact + Eigen::Vector3d(0.0, 0.0, -0.01));
  link.home = home;
  link.floor_m = 0.5;
  MasterCycle cycle(config("force-position"), device, link);
  cycle.start(0.0);
  const double dt = 1e-3, bound_n = device.spec().max_force_rate_n_per_s * dt;
  double t = 0.0, max_step = 0.0;
  Eigen::Vector3d prev = Eigen::Vector3d::Zero();
  bool rehomed = false;
  double force_before = 0.0;
  for (int i = 0; i < 8000; ++i, t += dt) {
    if (i == 2000) {
      force_before = cycle.device_force_n().norm();
      link.restart();
    }
    cycle.step(t);
    cycle.finish(t);
    max_step = std::max(max_step, (cycle.device_force_n() - prev).norm());
    prev = cycle.device_force_n();
    if (cycle.rehoming()) rehomed = true;
    if (cycle.rehoming()) {
      EXPECT_LE(cycle.device_force_n().norm(), force_before + 1e-9);
    }
  }
  EXPECT_GT(force_before, 0.3);
  EXPECT_TRUE(rehomed);
  EXPECT_EQ(cycle.rehomes(RehomeReason::kSlaveRestart), 1u);
  EXPECT_EQ(cycle.rehomes(), 1u);
  EXPECT_LE(max_step, bound_n + 1e-12);
  // after the path the slave is back under the device and the force is what it was
  EXPECT_LT((link.slave.position_m - cycle.last_sample().master_position_m).norm(), 1e-9);
  EXPECT_LT(link.slave.position_m.z(), 0.5);  // pressing again
  EXPECT_NEAR(cycle.device_force_n().norm(), force_before, 0.05);
  EXPECT_FALSE(cycle.metrics().verdict() == Verdict::kUnstable);
}

TEST(MasterCycle, ALinkThatComesBackReHomesAndAHeldCycleRendersNothing) {
  SimulatedDevice device(holding_device(Eigen::Vector3d::Zero()));
  RestartableLink link(Eigen::Vector3d(0.6, 0.0, 0.5));
  MasterCycle cycle(config("force-position"), device, link);
  cycle.start(0.0);
  double t = 0.0;
  const double dt = 1e-3;
  for (int i = 0; i < 1500; ++i, t += dt) {
    link.silent = i >= 500 && i < 800;  // 0.3 s without samples: the link is lost
    cycle.step(t);
    cycle.finish(t);
  }
  EXPECT_EQ(cycle.rehomes(RehomeReason::kLinkBack), 1u);
  EXPECT_FALSE(cycle.homing());
  // held: nothing rendered, the slave asked to hold, no session figures
  cycle.hold(true);
  for (int i = 0; i < 100; ++i, t += dt) {
    cycle.step(t);
    cycle.finish(t);
    EXPECT_TRUE(cycle.homing_cycle());
  }
  EXPECT_EQ(cycle.device_force_n(), Eigen::Vector3d::Zero());
  cycle.hold(false);
  cycle.rehome(t, RehomeReason::kTakeover);
  for (int i = 0; i < 1000 && cycle.homing(); ++i, t += dt) {
    cycle.step(t);
    cycle.finish(t);
  }
  EXPECT_FALSE(cycle.homing());
  EXPECT_EQ(cycle.rehomes(RehomeReason::kTakeover), 1u);
  EXPECT_EQ(cycle.rehomes(), 2u);
}

// Live tuning: a gain change ramps in (no force step), bad requests are rejected and counted
// and change nothing, and a delay change slews so that the channel never stalls or bunches.
TEST(MasterCycle, LiveTuningRampsTheForceInWithoutAStep) {
  SimulatedDevice device(holding_device(Eigen::Vector3d::Zero()));
  ServoLink link(Eigen::Vector3d(0.6, 0.0, 0.5));
  link.contact_force_n = Eigen::Vector3d(0.0, 0.0, 4.0);
  MasterCycle cycle(config("force-position"), device, link);
  cycle.start(0.0);
  double t = 0.0;
  auto run = [&](int cycles, double& max_change_n) {
    Eigen::Vector3d prev = cycle.device_force_n();
    for (int i = 0; i < cycles; ++i, t += 1e-3) {
      cycle.step(t);
      cycle.finish(t);
      max_change_n = std::max(max_change_n, (cycle.device_force_n() - prev).norm());
      prev = cycle.device_force_n();
    }
  };
  double settle = 0.0;
  run(500, settle);
  // K_f = 1: the contact force, felt (the held device's small motion adds a little damping)
  EXPECT_NEAR(cycle.device_force_n().z(), 4.0, 0.05);

  // rejected, counted, nothing changes
  TuningRequestData bad;
  bad.fields = kTuneForceGain;
  bad.values.force_gain = 1000.0;
  EXPECT_EQ(cycle.tune(bad, t), "force_gain = 1000 is outside [0, 10]");
  bad.values.force_gain = std::nan("");
  EXPECT_NE(cycle.tune(bad, t).find("force_gain = nan is outside"), std::string::npos);
  bad.fields = kTuneMasterStiffness;  // K_pm: not a force-position gain
  bad.values.master_stiffness_n_per_m = 100.0;
  EXPECT_EQ(cycle.tune(bad, t),
            "master_stiffness_n_per_m is not used by the force-position scheme");
  EXPECT_EQ(cycle.tunings_rejected(), 3u);
  EXPECT_EQ(cycle.tunings_accepted(), 0u);
  double unchanged = 0.0;
  run(100, unchanged);
  EXPECT_NEAR(cycle.device_force_n().z(), 4.0, 0.05);
  EXPECT_LT(unchanged, 1e-3);

  // K_f 1 -> 2 over 0.5 s: the felt force goes 4 -> 8 N in steps of 4 N * 1 ms / 0.5 s
  TuningRequestData good;
  good.fields = kTuneForceGain;
  good.values.force_gain = 2.0;
  good.ramp_s = 0.5;
  ASSERT_EQ(cycle.tune(good, t), "");
  double max_change = 0.0;
  run(1000, max_change);
  EXPECT_NEAR(cycle.device_force_n().z(), 8.0, 0.05);
  // 8 mN per cycle from the ramp, plus the damping's share (a step would be 4 N, and the safety
  // layer's own bound 1 N per cycle)
  EXPECT_LE(max_change, 4.0 * 1e-3 / 0.5 + 1e-3);
  EXPECT_GT(max_change, 4.0 * 1e-3 / 0.5 * 0.9);  // it did ramp, at that rate
  EXPECT_EQ(cycle.tunings_accepted(), 1u);
  EXPECT_DOUBLE_EQ(cycle.tuning().current().force_gain, 2.0);
  EXPECT_DOUBLE_EQ(cycle.controller().params().force_gain, 2.0);
}

TEST(MasterCycle, LiveDelayChangeSlewsWithoutStallingTheChannel) {
  SimulatedDevice device(holding_device(Eigen::Vector3d::Zero()));
  ServoLink link(Eigen::Vector3d(0.6, 0.0, 0.5));
  MasterCycle cycle(config("position-position"), device, link);
  cycle.start(0.0);
  TuningRequestData up;
  up.fields = kTuneForwardDelay;
  up.values.forward_delay_s = 0.1;
  up.ramp_s = 0.05;  // asked faster than a delay may move: it slews at 0.25 s/s (0.4 s)
  int longest_gap = 0, gap = 0;
  std::size_t delivered_before = 0;
  double t = 0.0;
  for (int i = 0; i < 3000; ++i, t += 1e-3) {
    if (i == 500) {
      ASSERT_EQ(cycle.tune(up, t), "");
      delivered_before = link.sent.size();
    }
    const std::size_t before = link.sent.size();
    cycle.step(t);
    cycle.finish(t);
    if (i >= 500) {
      gap = link.sent.size() == before ? gap + 1 : 0;
      longest_gap = std::max(longest_gap, gap);
    }
  }
  EXPECT_GT(delivered_before, 0u);
  // at 0.25 s/s a command arrives every 1.25 ms at most: never two empty cycles in a row (a
  // step of the delay would leave 100)
  EXPECT_LE(longest_gap, 1);
  // every command arrives, in order: 3000 issued, the last 100 ms still in flight
  for (std::size_t k = 1; k < link.sent.size(); ++k) {
    ASSERT_EQ(link.sent[k].seq, link.sent[k - 1].seq + 1);
  }
  EXPECT_NEAR(static_cast<double>(link.sent.size()), 2900.0, 2.0);
  EXPECT_DOUBLE_EQ(cycle.tuning().current().forward_delay_s, 0.1);
  EXPECT_EQ(cycle.forward().counters().lost_overflow, 0u);
}

// The workspace the device declares is enforced: a reading outside it (a driver fault, a
// miscalibration) renders nothing and commands a hold, is counted, and raises one event.
TEST(MasterCycle, AReadingOutsideTheDeclaredWorkspaceRendersNothingAndHolds) {
  SimulatedDeviceParams outside = holding_device(Eigen::Vector3d(0.3, 0.0, 0.0));  // box +-0.2 m
  outside.clamp_to_workspace = false;  // no hard stop: a driver that reports beyond its box
  SimulatedDevice device(outside);
  ServoLink link(Eigen::Vector3d(0.6, 0.0, 0.5));
  link.contact_force_n = Eigen::Vector3d(0.0, 0.0, 4.0);
  MasterCycle cycle(config("force-position"), device, link);
  cycle.start(0.0);
  for (int i = 0; i < 100; ++i) {
    cycle.step(i * 1e-3);
    cycle.finish(i * 1e-3);
    EXPECT_EQ(cycle.device_force_n(), Eigen::Vector3d::Zero());
    EXPECT_FALSE(link.sent.back().enabled);
  }
  EXPECT_EQ(cycle.workspace_violations(), 100u);
  int events = 0;
  sim::SimEvent e;
  while (cycle.safety().events().pop(e)) {
    if (e.kind == sim::EventKind::kLimit) ++events;
  }
  EXPECT_EQ(events, 1);
  // inside the box (within the 5 mm tolerance) nothing is counted
  SimulatedDevice inside(holding_device(Eigen::Vector3d(0.204, 0.0, 0.0)));
  ServoLink link2(Eigen::Vector3d(0.6, 0.0, 0.5));
  link2.contact_force_n = Eigen::Vector3d(0.0, 0.0, 4.0);
  MasterCycle ok(config("force-position"), inside, link2);
  ok.start(0.0);
  for (int i = 0; i < 100; ++i) {
    ok.step(i * 1e-3);
    ok.finish(i * 1e-3);
  }
  EXPECT_EQ(ok.workspace_violations(), 0u);
  EXPECT_GT(ok.device_force_n().norm(), 1.0);
}

TEST(MasterCycle, ASilentDriverHoldsFadesTheForceAndIsLeftOutOfTheFigures) {
  ExternalDevice device(DeviceSpec{}, 0.01);
  ServoLink link(Eigen::Vector3d(0.6, 0.0, 0.5));
  link.contact_force_n = Eigen::Vector3d(0.0, 0.0, 4.0);
  MasterCycleConfig cfg = config("force-position");
  cfg.driver_timeout_s = 0.1;
  MasterCycle cycle(cfg, device, link);
  ExternalDeviceSample hand;
  hand.engaged = true;
  auto feed = [&](std::uint64_t seq) {
    hand.seq = seq;
    device.on_sample(hand);
  };
  feed(1);
  cycle.start(0.0);
  int i = 0;
  for (; i < 500; ++i) {  // live: the contact force is rendered
    feed(static_cast<std::uint64_t>(i) + 2);
    cycle.step(i * 1e-3);
    cycle.finish(i * 1e-3);
  }
  const std::uint64_t live_samples = cycle.metrics().samples();
  ASSERT_GT(cycle.device_force_n().norm(), 2.0);
  EXPECT_FALSE(cycle.driver_silent());
  // the driver stops: stale after 10 ms, silent after 100 ms more
  double prev = cycle.device_force_n().norm();
  double max_step = 0.0;
  int silent_at = -1;
  for (; i < 1000; ++i) {
    cycle.step(i * 1e-3);
    cycle.finish(i * 1e-3);
    max_step = std::max(max_step, std::abs(cycle.device_force_n().norm() - prev));
    prev = cycle.device_force_n().norm();
    if (silent_at < 0 && cycle.driver_silent()) silent_at = i;
  }
  ASSERT_GT(silent_at, 500);
  EXPECT_LT(silent_at, 500 + 10 + 100 + 5);
  EXPECT_LE(max_step, DeviceSpec{}.max_force_rate_n_per_s * 1e-3 + 1e-9);  // 1 N per cycle
  EXPECT_EQ(cycle.device_force_n(), Eigen::Vector3d::Zero());
  EXPECT_FALSE(link.sent.back().enabled);  // the slave holds
  EXPECT_EQ(cycle.driver_silences(), 1u);
  // no cycle without a valid reading went into the figures
  EXPECT_LE(cycle.metrics().samples(), live_samples + 11);
  int events = 0;
  sim::SimEvent e;
  while (cycle.safety().events().pop(e)) {
    if (e.kind == sim::EventKind::kWatchdog) ++events;
  }
  EXPECT_EQ(events, 1);
  // the driver comes back: one more event, a re-homing, the silence closed and counted
  for (; i < 1200; ++i) {
    feed(static_cast<std::uint64_t>(i));
    cycle.step(i * 1e-3);
    cycle.finish(i * 1e-3);
  }
  EXPECT_FALSE(cycle.driver_silent());
  EXPECT_EQ(cycle.rehomes(RehomeReason::kDriverBack), 1u);
  EXPECT_NEAR(cycle.driver_silent_s(1.2), 0.49, 0.02);  // from the last valid reading
  EXPECT_EQ(cycle.driver_silences(), 1u);
}

}  // namespace
}  // namespace teleop::master
