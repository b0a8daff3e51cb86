// The master loop as the DDS node wires it, written out by hand (no LoopbackSession): this is
// the usage example of docs/control.md, kept compiling and correct by being a test. The
// "network" here is a pair of DelayChannels and the server's cycle in-process (WorldSlave); in
// the node the forward channel's output goes to the MasterCommand writer and the SlaveState
// reader feeds the backward channel.
#include <gtest/gtest.h>

#include "client/control/bilateral_controller.hpp"
#include "client/control/safety.hpp"
#include "client/device/simulated_device.hpp"
#include "client/metrics/session_metrics.hpp"
#include "client/net/delay_channel.hpp"
#include "server/node/world_slave.hpp"
#include "server/world/world_model.hpp"
#include "tests/support/alloc_counter.hpp"

using namespace teleop::master;
using namespace teleop;

namespace {

/// The server's cycle on a tool world with an elastic sphere (the default 25 cm radius, centre
/// 25 cm up, 2000 N/m), the tool starting at `tool_m`, stepped at 1 kHz.
teleop::server::WorldSlave sphere_slave(const Eigen::Vector3d& tool_m) {
  teleop::sim::ToolModel sp;
  teleop::sim::Obstacle sphere;
  sphere.kind = teleop::sim::Obstacle::Kind::kSphere;
  sphere.centre_m = Eigen::Vector3d(0.0, 0.0, 0.25);
  sphere.stiffness_n_per_m = 2000.0;
  sphere.damping_ns_per_m = 5.0;
  sp.add(sphere);
  return teleop::server::WorldSlave(teleop::sim::tool_world_model(sp, tool_m, 1.0 / 1e-3));
}

/// What one haptic cycle gives the session metrics.
MetricsSample metrics_sample(double now, double dt, const DeviceReading& r,
                             const ControlOutput& out, const SlaveSample& newest,
                             const Eigen::Vector3d& f, const WorkspaceMap& workspace,
                             const BilateralController& controller, const SafetyLayer& safety) {
  MetricsSample ms;
  ms.time_s = now;
  ms.dt_s = dt;
  ms.master_position_m = out.command.position_m;
  ms.slave_position_m = newest.position_m;
  ms.have_slave = newest.valid;
  ms.master_velocity_mps = r.linear_velocity_mps;
  ms.device_force_n = f;
  ms.environment_force_n = workspace.to_master_force(newest.contact_force_n);
  ms.in_contact = newest.in_contact;
  ms.force_limit_n = controller.force_limit_n();
  ms.link_ok = !safety.link_lost();
  ms.safety_scale = safety.scale();
  return ms;
}

}  // namespace

TEST(MasterLoopExample, HandWiredLoopPressesTheSphere) {
  // --- setup (allocates; outside the real-time loop) ---
  SimulatedDeviceParams dp;
  dp.script = press_slip_script(Eigen::Vector3d::Zero(), 0.02);  // Fig. 13 task
  SimulatedDevice device(dp);
  device.configure();
  device.activate();

  ControllerParams cp;
  cp.scheme = "position-position";                          // or "force-position"
  cp.workspace.offset_m = Eigen::Vector3d(0.0, 0.0, 0.55);  // master origin -> slave
  std::unique_ptr<BilateralController> controller = make_controller(cp.scheme);
  controller->configure(cp, device.spec());  // gains clamped to the spec
  controller->activate(device.read());

  DelayConfig net;  // e.g. from parse_delay_flags
  parse_delay_flags(net, {"--delay", "10ms", "--jitter", "1ms", "--loss", "1%", "--seed", "3"});
  DelayChannel<SlaveCommand> to_slave(net);
  net.seed += 1;
  DelayChannel<SlaveSample> to_master(net);

  SafetyLayer safety;
  safety.configure(SafetyParams{}, device.spec());
  SessionMetrics metrics;

  teleop::server::WorldSlave slave = sphere_slave(cp.workspace.to_slave_position(
      device.read().position_m));  // the world teleop_server would step
  SlaveCommand at_slave;
  at_slave.enabled = false;

  SlaveSample newest;       // newest slave sample at the master (valid = false until one)
  double last_rx_s = -1.0;  // master time it arrived
  const double dt = 1e-3;
  double max_force = 0.0;
  teleop::test::NoAllocScope no_alloc;
  for (int k = 0; k < 6000; ++k) {
    const double now = k * dt;
    // --- the haptic cycle ---
    const DeviceReading r = device.read();
    if (to_master.pop_newest(now, newest)) last_rx_s = now;  // node: take newest SlaveState
    const ControlOutput out = controller->update(r, newest, dt);
    const Eigen::Vector3d f =
        safety.filter(now, dt, out.force_n, last_rx_s, controller->force_limit_n(), metrics);
    device.write(f, out.torque_nm);
    to_slave.push(out.command, now);  // node: write MasterCommand when it leaves the channel

    metrics.update(metrics_sample(now, dt, r, out, newest, f, cp.workspace, *controller, safety));
    device.advance(dt);

    // --- the far side (teleop_server) ---
    to_slave.pop_newest(now, at_slave);
    slave.step(at_slave, dt);
    to_master.push(slave.sample(), now);
    max_force = std::max(max_force, f.norm());
  }
  EXPECT_EQ(no_alloc.allocations(), 0u);
  EXPECT_EQ(metrics.verdict(), Verdict::kStable) << metrics.summary_json();
  EXPECT_GT(metrics.contact_time_s(), 1.0);
  EXPECT_GT(max_force, 1.0);
  EXPECT_LE(max_force, device.spec().max_force_n);
  EXPECT_LT(metrics.position_error_rms_m(), 0.02);
  EXPECT_NEAR(to_slave.report().loss_fraction, 0.01, 0.01);
}
