// Haptic device layer: simulated device with operator model, replay, external adapter.
#include <gtest/gtest.h>

#include "tests/support/config_error.hpp"

#include <cmath>
#include <functional>
#include <vector>

#include "client/device/device_idl.hpp"
#include "client/device/external_device.hpp"
#include "client/device/replay_device.hpp"
#include "client/device/simulated_device.hpp"
#include "common/config/config.hpp"
#include "tests/support/alloc_counter.hpp"

using namespace teleop::master;
using namespace teleop;
using teleop::config::ConfigError;

namespace {

std::string error_of(const std::function<void()>& fn) { return teleop::test::config_error_of(fn); }

SimulatedDeviceParams step_params() {
  SimulatedDeviceParams p;
  p.script.kind = ScriptKind::kStep;
  p.script.start_m = Eigen::Vector3d(0.0, 0.0, 0.05);
  p.script.step_m = Eigen::Vector3d(0.02, 0.0, 0.0);
  p.script.step_time_s = 0.1;
  return p;
}

TEST(OperatorScript, PressSlipVisitsApproachContactPressSlipDepart) {
  const OperatorScript s = press_slip_script(Eigen::Vector3d(0.0, 0.0, 0.01), 0.02);
  const double leg = s.segment_s + s.dwell_s;
  // start above the top, touch the top, press below it, slip sideways, depart upwards
  EXPECT_NEAR(intended_pose(s, 0.0).position_m.z(), 0.01 + s.approach_height_m, 1e-12);
  EXPECT_NEAR(intended_pose(s, leg).position_m.z(), 0.01, 1e-12);
  EXPECT_NEAR(intended_pose(s, 2 * leg).position_m.z(), 0.01 - 0.02, 1e-12);
  EXPECT_NEAR(intended_pose(s, 3 * leg).position_m.x(), s.slip_m.x(), 1e-12);
  EXPECT_NEAR(intended_pose(s, 4 * leg).position_m.z(), 0.01 + s.approach_height_m, 1e-12);
  EXPECT_EQ(intended_pose(s, 4 * leg + 1.0).phase, 4);
  // velocity is the derivative of position (minimum-jerk segments)
  const double t = 1.7 * leg, h = 1e-6;
  const Eigen::Vector3d fd =
      (intended_pose(s, t + h).position_m - intended_pose(s, t - h).position_m) / (2 * h);
  EXPECT_NEAR((fd - intended_pose(s, t).velocity_mps).norm(), 0.0, 1e-6);
}

TEST(OperatorScript, CircleStartsAtStartAndHasRadius) {
  OperatorScript s;
  s.kind = ScriptKind::kCircle;
  s.start_m = Eigen::Vector3d(0.01, 0.02, 0.03);
  EXPECT_NEAR((intended_pose(s, 0.0).position_m - s.start_m).norm(), 0.0, 1e-12);
  const Eigen::Vector3d centre = s.start_m - s.circle_radius_m * s.circle_u;
  for (double t : {0.3, 0.9, 1.7}) {
    EXPECT_NEAR((intended_pose(s, t).position_m - centre).norm(), s.circle_radius_m, 1e-12);
  }
  EXPECT_THROW(parse_script_kind("spiral"), ConfigError);
  EXPECT_EQ(parse_script_kind("press-slip"), ScriptKind::kPressSlip);
}

TEST(SimulatedDevice, HandTracksAStepWithoutForce) {
  SimulatedDevice dev(step_params());
  dev.configure();
  dev.activate();
  for (int i = 0; i < 3000; ++i) {
    dev.write(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
    dev.advance(1e-3);
  }
  const DeviceReading r = dev.read();
  EXPECT_TRUE(r.valid);
  EXPECT_NEAR(r.position_m.x(), 0.02, 1e-4);
  EXPECT_NEAR(r.linear_velocity_mps.norm(), 0.0, 1e-3);
}

TEST(SimulatedDevice, StaticForceDeflectsTheHandByFOverK) {
  SimulatedDeviceParams p;
  p.script.kind = ScriptKind::kHold;
  SimulatedDevice dev(p);
  dev.activate();
  const Eigen::Vector3d f(0.0, 0.0, 3.0);
  for (int i = 0; i < 5000; ++i) {
    dev.write(f, Eigen::Vector3d::Zero());
    dev.advance(1e-3);
  }
  // the hand spring balances the device force: x = F / K_h
  EXPECT_NEAR(dev.read().position_m.z(), 3.0 / p.hand.stiffness_n_per_m, 1e-5);
  EXPECT_NEAR(dev.hand_force_n().z(), -3.0, 1e-3);
}

TEST(SimulatedDevice, ClipsForceToSpecAndIsDeterministicAndAllocationFree) {
  SimulatedDeviceParams p = step_params();
  p.script.tremor_amplitude_m = 1e-4;
  SimulatedDevice a(p), b(p);
  a.activate();
  b.activate();
  {
    teleop::test::NoAllocScope scope;
    for (int i = 0; i < 2000; ++i) {
      const Eigen::Vector3d f(50.0 * std::sin(0.01 * i), 0.0, 0.0);  // beyond the spec
      a.write(f, Eigen::Vector3d::Zero());
      b.write(f, Eigen::Vector3d::Zero());
      a.advance(1e-3);
      b.advance(1e-3);
      EXPECT_LE(a.applied_force_n().norm(), p.spec.max_force_n + 1e-12);
      const DeviceReading ra = a.read(), rb = b.read();
      ASSERT_EQ(ra.position_m, rb.position_m);
    }
    EXPECT_EQ(scope.allocations(), 0u);
  }
}

TEST(SimulatedDevice, InactiveDeviceRendersNothing) {
  SimulatedDevice dev(step_params());
  dev.configure();
  dev.write(Eigen::Vector3d(5, 0, 0), Eigen::Vector3d::Zero());
  dev.advance(1e-3);
  EXPECT_FALSE(dev.read().valid);
  EXPECT_EQ(dev.applied_force_n().norm(), 0.0);
}

TEST(ReplayDevice, InterpolatesPositionAndOrientation) {
  const auto samples = parse_replay_csv(
      "time_s,x,y,z,qw,qx,qy,qz\n"
      "0.0,0,0,0,1,0,0,0\n"
      "1.0,0.1,0,0,0.7071067811865476,0,0,0.7071067811865476\n",
      "mem.csv");
  ReplayDevice dev(samples);
  dev.activate();
  dev.advance(0.25);
  const DeviceReading r = dev.read();
  EXPECT_TRUE(r.valid);
  EXPECT_NEAR(r.position_m.x(), 0.025, 1e-12);
  EXPECT_NEAR(r.linear_velocity_mps.x(), 0.1, 1e-12);
  // a quarter of a 90 degree turn about z
  EXPECT_NEAR(Eigen::AngleAxisd(r.orientation).angle(), 0.25 * M_PI / 2, 1e-9);
  EXPECT_NEAR(r.angular_velocity_radps.z(), M_PI / 2, 1e-9);
  dev.advance(5.0);
  EXPECT_TRUE(dev.finished());
  EXPECT_NEAR(dev.read().position_m.x(), 0.1, 1e-12);
}

// A teleop_master --log file is a replay file as it is: the header names t_s and the
// device's own pose dev_x .. dev_qz among the other columns.
TEST(ReplayDevice, AMasterLogIsReadByItsHeader) {
  const std::string log =
      "t_s,phase,seq,xm_x,dev_x,dev_y,dev_z,dev_qw,dev_qx,dev_qy,dev_qz\n"
      "0.001,0,1,9,0.10,0.20,0.30,1,0,0,0\n"
      "0.002,1,2,9,0.11,0.21,0.31,0.7071067811865476,0.7071067811865476,0,0\n";
  const auto s = parse_replay_csv(log, "master_log.csv");
  ASSERT_EQ(s.size(), 2u);
  EXPECT_DOUBLE_EQ(s[0].time_s, 0.001);
  EXPECT_DOUBLE_EQ(s[1].position_m.x(), 0.11);
  EXPECT_DOUBLE_EQ(s[1].position_m.z(), 0.31);
  EXPECT_NEAR(s[1].orientation.x(), 0.7071067811865476, 1e-12);
  // a row shorter than the header is named
  const std::string msg =
      error_of([&] { parse_replay_csv(log + "0.003,1,3\n", "master_log.csv"); });
  EXPECT_NE(msg.find("master_log.csv:4"), std::string::npos) << msg;
  EXPECT_NE(msg.find("expected 11 fields as in the header"), std::string::npos) << msg;
}

TEST(ReplayDevice, BadCsvNamesFileLineAndColumn) {
  std::string msg = error_of([] { parse_replay_csv("0,0,0,0\n0.1,0,zero,0\n", "rec.csv"); });
  EXPECT_NE(msg.find("rec.csv:2:7"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'y'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("zero"), std::string::npos) << msg;

  msg = error_of([] { parse_replay_csv("time_s,x,y,z\n0,0,0,0\n0,1,1,1\n", "t.csv"); });
  EXPECT_NE(msg.find("t.csv:3:1"), std::string::npos) << msg;
  EXPECT_NE(msg.find("increase"), std::string::npos) << msg;

  msg = error_of([] { parse_replay_csv("0,0,0\n", "short.csv"); });
  EXPECT_NE(msg.find("short.csv:1"), std::string::npos) << msg;
  EXPECT_NE(msg.find("found 3"), std::string::npos) << msg;

  msg = error_of([] {
    ReplayDevice d("/nonexistent/replay.csv");
    d.configure();
  });
  EXPECT_NE(msg.find("/nonexistent/replay.csv"), std::string::npos) << msg;
}

TEST(ReplayDevice, ValuesOutsideTheirBoundAreRefusedNamingRowColumnValueAndRange) {
  // a finite but absurd position (1e308 m) is refused, not played
  std::string msg = error_of([] { parse_replay_csv("0,0,0,0\n0.1,0,1e308,0\n", "big.csv"); });
  EXPECT_NE(msg.find("big.csv:2:7"), std::string::npos) << msg;
  EXPECT_NE(msg.find("row 2, column 'y': 1e308"), std::string::npos) << msg;
  EXPECT_NE(msg.find("[-10, 10] m"), std::string::npos) << msg;
  // named columns, a master log's dev_z
  msg = error_of([] { parse_replay_csv("t_s,dev_x,dev_y,dev_z\n0,0,0,-11\n", "log.csv"); });
  EXPECT_NE(msg.find("log.csv:2:7"), std::string::npos) << msg;
  EXPECT_NE(msg.find("column 'z': -11"), std::string::npos) << msg;
  // time and quaternion components
  msg = error_of([] { parse_replay_csv("2e6,0,0,0\n", "t.csv"); });
  EXPECT_NE(msg.find("column 'time_s': 2e6 is outside the allowed range [-1e6, 1e6] s"),
            std::string::npos)
      << msg;
  msg = error_of([] { parse_replay_csv("0,0,0,0,1e200,0,0,0\n", "q.csv"); });
  EXPECT_NE(msg.find("column 'qw': 1e200"), std::string::npos) << msg;
  // the bound itself is allowed
  EXPECT_EQ(parse_replay_csv("0,10,-10,0\n", "edge.csv").size(), 1u);
}

TEST(ExternalDevice, StaleSampleInvalidatesReadingAndZeroesCommand) {
  ExternalDevice dev(DeviceSpec{}, 0.01);
  dev.activate();
  EXPECT_FALSE(dev.read().valid);  // nothing received yet
  ExternalDeviceSample s;
  s.seq = 1;
  s.engaged = true;
  s.position_m = Eigen::Vector3d(0.01, 0.02, 0.03);
  EXPECT_TRUE(dev.on_sample(s));
  EXPECT_FALSE(dev.on_sample(s));  // same seq again is ignored
  dev.write(Eigen::Vector3d(100.0, 0.0, 0.0), Eigen::Vector3d::Zero());
  dev.advance(0.005);
  DeviceReading r = dev.read();
  EXPECT_TRUE(r.valid);
  EXPECT_EQ(r.position_m, s.position_m);
  ExternalDeviceCommand c = dev.next_command();
  EXPECT_TRUE(c.enable);
  EXPECT_NEAR(c.force_n.x(), DeviceSpec{}.max_force_n, 1e-12);  // saturated to the spec
  EXPECT_EQ(c.state_seq, 1u);
  dev.advance(0.01);  // older than the timeout now
  EXPECT_FALSE(dev.read().valid);
  c = dev.next_command();
  EXPECT_FALSE(c.enable);
  EXPECT_EQ(c.force_n.norm(), 0.0);
  EXPECT_EQ(dev.stale_events(), 1u);
  s.seq = 2;
  dev.on_sample(s);
  EXPECT_TRUE(dev.read().valid);
  // a restarted driver (seq from 0) is accepted once the link is stale
  s.seq = 0;
  EXPECT_FALSE(dev.on_sample(s));
  dev.advance(0.02);
  EXPECT_TRUE(dev.on_sample(s));
  EXPECT_TRUE(dev.read().valid);
}

TEST(ExternalDevice, ConvertsFromAndToTheIdlTypes) {
  teleop::DeviceState m;
  m.seq(7);
  m.position_m({0.1, 0.2, 0.3});
  m.orientation_wxyz({2.0, 0.0, 0.0, 0.0});  // not normalised on the wire
  m.engaged(true);
  m.buttons(3);
  const ExternalDeviceSample s = from_idl(m);
  EXPECT_EQ(s.seq, 7u);
  EXPECT_NEAR(s.position_m.y(), 0.2, 1e-15);
  EXPECT_NEAR(s.orientation.w(), 1.0, 1e-15);
  EXPECT_EQ(s.buttons, 3u);
  ExternalDeviceCommand c;
  c.seq = 9;
  c.force_n = Eigen::Vector3d(1, 2, 3);
  c.enable = true;
  const teleop::DeviceCommand out = to_idl(c, 1234);
  EXPECT_EQ(out.seq(), 9u);
  EXPECT_EQ(out.time_ns(), 1234);
  EXPECT_EQ(out.force_n()[2], 3.0);
  EXPECT_TRUE(out.enable());
}

}  // namespace
