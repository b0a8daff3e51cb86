// The safety layer (link loss, saturation and energy cuts, fades), checked on the in-process loop.
#include <gtest/gtest.h>

#include "tests/support/config_error.hpp"

#include <cmath>
#include <functional>

#include "client/analysis/press_scenario.hpp"
#include "client/analysis/stability_analysis.hpp"
#include "client/control/bilateral_controller.hpp"
#include "client/control/safety.hpp"
#include "client/device/simulated_device.hpp"
#include "client/sim/loopback_session.hpp"
#include "common/dds/teleop_idl.hpp"
#include "common/sim/tool.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/support/master_helpers.hpp"
#include "tests/support/press_world.hpp"

using namespace teleop::master;
using namespace teleop;
using teleop::test::scenario;
using teleop::test::SteadyContact;

namespace {

TEST(Safety, LostLinkFadesForceToZeroAndBack) {
  SafetyLayer safety;
  SafetyParams p;
  p.link_timeout_s = 0.1;
  p.link_fade_s = 0.2;
  p.thermal_limit = false;
  safety.configure(p, DeviceSpec{});
  SessionMetrics metrics;
  const Eigen::Vector3d f(0.0, 0.0, 4.0);
  const double dt = 1e-3;
  double last_rx = 0.0;
  double t = 0.0;
  for (; t < 1.0; t += dt) {
    last_rx = t;  // samples arriving
    const double z = safety.filter(t, dt, f, last_rx, 10.0, metrics).z();
    // 4 N from zero at the spec's rate bound (1 N per cycle), then held
    if (t > 0.0045) {
      EXPECT_NEAR(z, 4.0, 1e-12) << t;
    }
  }
  // the link dies at t = 1.0: nothing for 0.1 s, then a fade of 0.2 s
  double at_timeout = 0, mid_fade = 0, after = 0;
  for (; t < 1.6; t += dt) {
    const double z = safety.filter(t, dt, f, last_rx, 10.0, metrics).z();
    if (std::fabs(t - 1.09) < 0.5 * dt) at_timeout = z;
    if (std::fabs(t - 1.2) < 0.5 * dt) mid_fade = z;
    if (t > 1.31) after = std::max(after, std::fabs(z));
  }
  EXPECT_NEAR(at_timeout, 4.0, 1e-12);
  EXPECT_GT(mid_fade, 0.5);
  EXPECT_LT(mid_fade, 3.5);
  EXPECT_EQ(after, 0.0);
  EXPECT_TRUE(safety.link_lost());
  // the link comes back: the force ramps in again (no jump)
  const double first = safety.filter(t, dt, f, t, 10.0, metrics).z();
  EXPECT_LT(first, 0.1);
  for (int i = 0; i < 300; ++i) {
    t += dt;
    safety.filter(t, dt, f, t, 10.0, metrics);
  }
  t += dt;
  EXPECT_NEAR(safety.filter(t, dt, f, t, 10.0, metrics).z(), 4.0, 1e-12);
  teleop::sim::SimEvent e;
  int watchdog = 0;
  while (safety.events().pop(e)) watchdog += e.kind == teleop::sim::EventKind::kWatchdog;
  EXPECT_EQ(watchdog, 2);  // lost, back
}

TEST(Safety, LostLinkInTheLoopFadesDeviceForce) {
  // steady contact, then the slave->master link dies: the master holds a stale contact force
  SteadyContact sc(scenario("force-position", Environment::kSphere, 2000, 1.0, 0.0));
  sc.setup.loop.duration_s = 2.5;
  SimulatedDevice dev(sc.setup.device);
  teleop::server::WorldSlave slave(teleop::test::press_world(sc.setup));
  LoopbackSession session(sc.setup.loop, dev, slave);
  session.start();
  while (session.time_s() < 1.5) session.step();
  ASSERT_GT(session.device_force_n().norm(), 1.0);
  session.set_backward_outage(true);
  const double timeout = sc.setup.loop.safety.link_timeout_s;
  const double fade = sc.setup.loop.safety.link_fade_s;
  double during_timeout = 0.0;
  while (session.step()) {
    const double since = session.time_s() - 1.5;
    if (since < timeout - 0.005) during_timeout = session.device_force_n().norm();
    if (since > timeout + fade + 0.005) {
      EXPECT_EQ(session.device_force_n().norm(), 0.0) << since;
      EXPECT_GT(session.controller_force_n().norm(), 1.0);  // the stale force is still asked for
    }
  }
  EXPECT_GT(during_timeout, 1.0);  // not cut before the timeout
  EXPECT_TRUE(session.safety().link_lost());
  EXPECT_FALSE(session.safety().cut());
}

TEST(Safety, ForceAtTheLimitTooLongCutsAndLatches) {
  SafetyLayer safety;
  SafetyParams p;
  p.saturation_limit_s = 0.2;
  p.cut_fade_s = 0.05;
  p.thermal_limit = false;
  safety.configure(p, DeviceSpec{});
  SessionMetrics metrics;
  double t = 0.0;
  for (; t < 0.5; t += 1e-3) safety.filter(t, 1e-3, Eigen::Vector3d(10, 0, 0), t, 10.0, metrics);
  EXPECT_TRUE(safety.cut());
  EXPECT_NEAR(safety.cut_time_s(), 0.2, 0.01);
  // latched: a small force later stays cut until rearm()
  EXPECT_EQ(safety.filter(t, 1e-3, Eigen::Vector3d(1, 0, 0), t, 10.0, metrics).norm(), 0.0);
  safety.rearm();
  for (int i = 0; i < 400; ++i) {
    t += 1e-3;
    safety.filter(t, 1e-3, Eigen::Vector3d(1, 0, 0), t, 10.0, metrics);
  }
  EXPECT_NEAR(safety.filter(t, 1e-3, Eigen::Vector3d(1, 0, 0), t, 10.0, metrics).x(), 1.0, 1e-12);
}

TEST(Safety, ThermalLimitClampsToContinuousForceAndNaNIsZeroed) {
  SafetyLayer safety;
  safety.configure(SafetyParams{}, DeviceSpec{});
  SessionMetrics metrics;
  double out = 0.0;
  for (double t = 0.0; t < 5.0; t += 1e-3) {
    out = safety.filter(t, 1e-3, Eigen::Vector3d(0, 8.0, 0), t, 10.0, metrics).norm();
  }
  EXPECT_NEAR(out, DeviceSpec{}.max_continuous_force_n, 1e-9);
  // a NaN force is replaced by zero, reached at the rate bound (6 N at 1 N per cycle)
  const Eigen::Vector3d nan(std::nan(""), 0, 0);
  const double bound_n = DeviceSpec{}.max_force_rate_n_per_s * 1e-3;
  EXPECT_NEAR(safety.filter(5.0, 1e-3, nan, 5.0, 10.0, metrics).norm(), out - bound_n, 1e-9);
  for (int i = 1; i < 6; ++i) safety.filter(5.0 + i * 1e-3, 1e-3, nan, 5.0, 10.0, metrics);
  EXPECT_EQ(safety.filter(5.006, 1e-3, nan, 5.0, 10.0, metrics).norm(), 0.0);
  EXPECT_EQ(safety.faults(), 7u);
}

TEST(Safety, TheForceNeverChangesFasterThanTheSpecsRateBound) {
  SafetyLayer safety;
  DeviceSpec spec;  // 10 N peak, 1000 N/s
  SafetyParams p;
  p.thermal_limit = false;
  safety.configure(p, spec);
  SessionMetrics metrics;
  const double dt = 1e-3, bound_n = spec.max_force_rate_n_per_s * dt;
  // the controller asks for a step of 8 N, then a reversal to -8 N, then a NaN
  Eigen::Vector3d prev = Eigen::Vector3d::Zero();
  int cycles_to_8n = -1;
  for (int i = 0; i < 400; ++i) {
    const double t = 1.0 + i * dt;
    Eigen::Vector3d ask(8.0, 0.0, 0.0);
    if (i >= 100) ask = Eigen::Vector3d(-8.0, 0.0, 0.0);
    if (i == 300) ask.x() = std::nan("");
    const Eigen::Vector3d f = safety.filter(t, dt, ask, t, 10.0, metrics);
    EXPECT_LE((f - prev).norm(), bound_n + 1e-12) << "cycle " << i;
    if (cycles_to_8n < 0 && f.x() >= 8.0 - 1e-12) cycles_to_8n = i + 1;
    prev = f;
  }
  EXPECT_EQ(cycles_to_8n, 8);  // 8 N at 1 N per cycle
  EXPECT_LE(safety.max_step_n(), bound_n + 1e-12);
  EXPECT_GE(safety.rate_limited_cycles(), 7u + 15u);  // the rise, the reversal
  EXPECT_EQ(safety.faults(), 1u);
  // a cycle with nothing to render brings the force to zero at the same rate
  const Eigen::Vector3d before = safety.last_output_n();
  const Eigen::Vector3d held = safety.hold_zero(dt);
  EXPECT_NEAR((held - before).norm(), std::min(bound_n, before.norm()), 1e-12);
  for (int i = 0; i < 100; ++i) safety.hold_zero(dt);
  EXPECT_EQ(safety.last_output_n(), Eigen::Vector3d::Zero());
}

TEST(Safety, FadeInAfterAReHomingStartsFromZero) {
  SafetyLayer safety;
  SafetyParams p;
  p.thermal_limit = false;
  safety.configure(p, DeviceSpec{});
  SessionMetrics metrics;
  safety.fade_in();
  const Eigen::Vector3d ask(0.1, 0.0, 0.0);  // small: the fade, not the rate bound, shapes it
  const double dt = 1e-3;
  double prev = 0.0;
  for (int i = 0; i < 300; ++i) {
    const Eigen::Vector3d f = safety.filter(1.0 + i * dt, dt, ask, 1.0 + i * dt, 10.0, metrics);
    EXPECT_GE(f.x(), prev - 1e-15);
    prev = f.x();
    if (i == 99) {
      EXPECT_NEAR(f.x(), 0.05, 1e-3);  // half-way through the 0.2 s fade
    }
  }
  EXPECT_NEAR(prev, 0.1, 1e-12);
}

}  // namespace
