// The bilateral controllers (position-position, force-position), checked on the in-process loop.
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

std::string error_of(const std::function<void()>& fn) { return teleop::test::config_error_of(fn); }

TEST(PositionPosition, TracksInFreeMotionAtZeroDelay) {
  PressScenario s = scenario("position-position", Environment::kSphere, 2000, 400, 0.0);
  PressSetup setup = build_press_setup(s);
  // a circle well above the sphere: free motion only
  setup.device.script.kind = ScriptKind::kCircle;
  setup.device.script.start_m = Eigen::Vector3d(0.0, 0.0, 0.1);
  setup.device.script.tremor_amplitude_m = 0.0;
  setup.loop.duration_s = 4.0;
  SimulatedDevice dev(setup.device);
  teleop::server::WorldSlave slave(teleop::test::press_world(setup));
  LoopbackSession session(setup.loop, dev, slave);
  session.run();
  const SessionMetrics& m = session.metrics();
  EXPECT_EQ(m.verdict(), Verdict::kStable);
  EXPECT_EQ(m.contact_time_s(), 0.0);
  // stated tracking error: RMS under 2 mm, max under 5 mm on a 3 cm circle at 0.5 Hz
  EXPECT_LT(m.position_error_rms_m(), 2e-3);
  EXPECT_LT(m.position_error_max_m(), 5e-3);
}

TEST(PositionPosition, FeltForceMatchesContactForceInSteadyContact) {
  SteadyContact sc(scenario("position-position", Environment::kSphere, 2000, 400, 0.0));
  SimulatedDevice dev(sc.setup.device);
  teleop::server::WorldSlave slave(teleop::test::press_world(sc.setup));
  LoopbackSession session(sc.setup.loop, dev, slave);
  session.run();
  const Eigen::Vector3d f_dev = session.device_force_n();
  const Eigen::Vector3d f_env = slave.sample().contact_force_n;
  ASSERT_TRUE(slave.sample().in_contact);
  ASSERT_GT(f_env.z(), 1.0);  // a real press
  EXPECT_NEAR((f_dev - f_env).norm(), 0.0, 0.02 * f_env.norm() + 0.02)
      << "device " << f_dev.transpose() << " env " << f_env.transpose();
  EXPECT_EQ(session.metrics().verdict(), Verdict::kStable);
}

TEST(ForcePosition, RendersSpringForceStatically) {
  for (double k : {500.0, 2000.0, 8000.0}) {
    SteadyContact sc(scenario("force-position", Environment::kWall, k, 1.0, 0.0));
    sc.setup.slave.obstacles[1].damping_ns_per_m = 5.0;
    SimulatedDevice dev(sc.setup.device);
    teleop::server::WorldSlave slave(teleop::test::press_world(sc.setup));
    LoopbackSession session(sc.setup.loop, dev, slave);
    session.run();
    const double x = slave.sample().penetration_m;
    ASSERT_GT(x, 1e-4) << k;
    // F = K_f k x (K_f = 1, unit scaling), pointing out of the wall
    EXPECT_NEAR(session.device_force_n().z(), k * x, 0.02 * k * x) << k;
    EXPECT_NEAR(session.device_force_n().head<2>().norm(), 0.0, 0.05);
  }
}

TEST(ForcePosition, ForceScalingAndGainMultiply) {
  ControllerParams p;
  p.scheme = "force-position";
  p.force_gain = 0.5;
  p.workspace.force_scale = 0.4;
  p.master_damping_ns_per_m = 0.0;
  auto c = make_controller(p.scheme);
  c->configure(p, DeviceSpec{});
  DeviceReading r;
  r.valid = true;
  c->activate(r);
  SlaveSample s;
  s.valid = true;
  s.contact_force_n = Eigen::Vector3d(0.0, 0.0, 10.0);
  const ControlOutput out = c->update(r, s, 1e-3);
  EXPECT_NEAR(out.force_n.z(), 0.5 * 0.4 * 10.0, 1e-12);
}

TEST(Controller, WorkspaceMapScalesPositionAndClampsGainsToSpec) {
  ControllerParams p;
  p.scheme = "position-position";
  p.workspace.offset_m = Eigen::Vector3d(0.0, 0.0, 0.5);
  p.workspace.position_scale = 2.0;
  p.slave_stiffness_n_per_m = 2500.0;  // derived K_pm = 2 * 1 * 2500 = 5000 > spec 3000
  p.master_damping_ns_per_m = 100.0;   // > spec 20
  auto c = make_controller(p.scheme);
  DeviceSpec spec;
  c->configure(p, spec);
  EXPECT_EQ(c->master_stiffness_n_per_m(), spec.max_stiffness_n_per_m);
  EXPECT_EQ(c->master_damping_ns_per_m(), spec.max_damping_ns_per_m);
  DeviceReading r;
  r.valid = true;
  r.position_m = Eigen::Vector3d(0.01, 0.0, 0.0);
  c->activate(r);
  SlaveSample s;
  s.valid = true;
  s.position_m = Eigen::Vector3d(0.02, 0.0, 0.5);  // = master x 0.01 in master frame
  const ControlOutput out = c->update(r, s, 1e-3);
  EXPECT_NEAR(out.command.position_m.x(), 0.02, 1e-12);
  EXPECT_NEAR(out.command.position_m.z(), 0.5, 1e-12);
  EXPECT_NEAR(out.force_n.norm(), 0.0, 1e-12);
  // a large error saturates at the spec's peak force
  s.position_m = Eigen::Vector3d(1.0, 0.0, 0.5);
  const ControlOutput sat = c->update(r, s, 1e-3);
  EXPECT_TRUE(sat.saturated);
  EXPECT_NEAR(sat.force_n.norm(), spec.max_force_n, 1e-9);
  EXPECT_EQ(sat.command.seq, 2u);
}

TEST(Controller, WorkspaceMapWithRotationRoundTrips) {
  WorkspaceMap w;
  w.offset_m = Eigen::Vector3d(0.1, -0.2, 0.55);
  w.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));
  w.position_scale = 2.5;
  w.force_scale = 0.3;
  const Eigen::Vector3d x(0.01, 0.02, -0.03), f(1.0, -2.0, 0.5);
  EXPECT_NEAR((w.to_master_position(w.to_slave_position(x)) - x).norm(), 0.0, 1e-15);
  EXPECT_NEAR((w.to_master_force(w.to_slave_force(f)) - f).norm(), 0.0, 1e-14);
  EXPECT_NEAR(w.to_slave_velocity(x).norm(), 2.5 * x.norm(), 1e-15);
  EXPECT_NEAR(w.to_master_force(f).norm(), 0.3 * f.norm(), 1e-15);
}

TEST(Controller, BadParamsAndNamesGiveClearErrors) {
  std::string m = error_of([] { make_controller("wave"); });
  EXPECT_NE(m.find("position-position, force-position"), std::string::npos) << m;
  m = error_of([] {
    ControllerParams p;
    p.master_damping_ns_per_m = -1;
    p.validate();
  });
  EXPECT_NE(m.find("master_damping_ns_per_m"), std::string::npos) << m;
  m = error_of([] {
    controller_params_from_yaml(
        teleop::config::Node::parse("controller: {scheme: force-position, force_gain: 500}",
                                    "ctl.yaml")
            .at("controller"));
  });
  EXPECT_NE(m.find("ctl.yaml"), std::string::npos) << m;
  EXPECT_NE(m.find("controller.force_gain"), std::string::npos) << m;
  const ControllerParams ok = controller_params_from_yaml(
      teleop::config::Node::parse("{scheme: force-position, force_gain: 0.5, workspace: "
                                  "{offset_m: [0, 0, 0.55], position_scale: 2}}"));
  EXPECT_EQ(ok.scheme, "force-position");
  EXPECT_DOUBLE_EQ(ok.workspace.position_scale, 2.0);
  EXPECT_DOUBLE_EQ(ok.workspace.offset_m.z(), 0.55);
}

TEST(Controller, UpdateAndWholeLoopAllocateNothing) {
  for (const char* scheme : {"position-position", "force-position"}) {
    PressScenario s = scenario(scheme, Environment::kSphere, 2000, 0.0, 0.05);
    s.jitter_s = 0.002;
    const PressSetup setup = build_press_setup(s);
    SimulatedDevice dev(setup.device);
    teleop::server::WorldSlave slave(teleop::test::press_world(setup));
    LoopbackSession session(setup.loop, dev, slave);
    session.start();
    for (int i = 0; i < 100; ++i) session.step();  // warm up
    char row[512];
    teleop::test::NoAllocScope scope;
    for (int i = 0; i < 3000; ++i) {
      session.step();
      session.metrics().format_csv_row(session.last_sample(), row, sizeof(row));
    }
    EXPECT_EQ(scope.allocations(), 0u) << scheme;
  }
}

}  // namespace
