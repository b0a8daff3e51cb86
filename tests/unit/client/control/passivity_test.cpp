// Wave variables and time-domain passivity: the transforms, the energy bookkeeping of the
// channel, stability where position-position fails, drift, bad input, no allocation.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "client/analysis/press_scenario.hpp"
#include "client/analysis/stability_analysis.hpp"
#include "client/control/bilateral_controller.hpp"
#include "client/control/schemes/tdpa.hpp"
#include "client/control/schemes/wave_variables.hpp"
#include "client/device/simulated_device.hpp"
#include "client/sim/loopback_session.hpp"
#include "common/control/slave_port.hpp"
#include "common/control/time_domain_passivity.hpp"
#include "common/control/wave_variables.hpp"
#include "common/dds/teleop_idl.hpp"
#include "common/sim/tool.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/support/config_error.hpp"
#include "tests/support/master_helpers.hpp"
#include "tests/support/press_world.hpp"

using namespace teleop::master;
using namespace teleop;
using teleop::test::scenario;
namespace pv = teleop::passivity;
using Eigen::Vector3d;

namespace {

/// Operator script: from `start_z` above the touching point to `end_z`, in `move_s`, then
/// holding still (tremor on) until `duration_s`.
PressSetup hold_setup(PressScenario s, double start_z, double end_z, double move_s,
                      double duration_s) {
  PressSetup setup = build_press_setup(s);
  setup.device.script.kind = ScriptKind::kStep;
  setup.device.script.start_m = Vector3d(0.0, 0.0, start_z);
  setup.device.script.step_m = Vector3d(0.0, 0.0, end_z - start_z);
  setup.device.script.step_time_s = move_s;
  setup.loop.duration_s = duration_s;
  return setup;
}

struct RunResult {
  Verdict verdict;
  std::string reason;
  bool cut;
  double max_force_n;
  double contact_s;
  double final_error_m;  ///< |x_m (slave frame) - x_s| at the end
};

RunResult run(const PressSetup& setup) {
  SimulatedDevice dev(setup.device);
  teleop::server::WorldSlave slave(teleop::test::press_world(setup));
  LoopbackSession session(setup.loop, dev, slave);
  session.run();
  const SessionMetrics& m = session.metrics();
  return {m.verdict(),
          m.verdict_reason(),
          session.safety().cut(),
          m.max_device_force_n(),
          m.contact_time_s(),
          (session.last_sample().master_position_m - slave.sample().position_m).norm()};
}

// --- wave transforms ----------------------------------------------------------------------

TEST(WaveVariables, TransformsRoundTripAndKeepThePowerIdentity) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> d(-5.0, 5.0);
  for (int i = 0; i < 200; ++i) {
    const double b = 0.5 + std::fabs(d(rng)) * 4.0;
    const Vector3d xdot(d(rng), d(rng), d(rng)), f(d(rng), d(rng), d(rng));
    Vector3d u, v, xdot2, f2;
    pv::wave_encode(b, xdot, f, u, v);
    pv::wave_decode(b, u, v, xdot2, f2);
    ASSERT_NEAR((xdot2 - xdot).norm(), 0.0, 1e-12);
    ASSERT_NEAR((f2 - f).norm(), 0.0, 1e-12);
    // power into the channel = (u^2 - v^2) / 2
    ASSERT_NEAR(f.dot(xdot), 0.5 * (u.squaredNorm() - v.squaredNorm()), 1e-10);

    // master port: (xdot, v received) -> (F, u) is the same port relation
    Vector3d fm, um, ue, ve;
    pv::wave_master(b, xdot, v, fm, um);
    pv::wave_encode(b, xdot, fm, ue, ve);
    ASSERT_NEAR((ue - um).norm(), 0.0, 1e-12);
    ASSERT_NEAR((ve - v).norm(), 0.0, 1e-12);
    // slave port, both terminations: (u received, F_e) -> (xdot, v), same relation
    for (bool matched : {false, true}) {
      Vector3d xs, vs, fport;
      pv::wave_slave(b, matched, u, f, xs, vs, fport);
      Vector3d u2, v2;
      pv::wave_encode(b, xs, fport, u2, v2);
      ASSERT_NEAR((u2 - u).norm(), 0.0, 1e-10) << matched;
      ASSERT_NEAR((v2 - vs).norm(), 0.0, 1e-10) << matched;
      ASSERT_NEAR(fport.dot(xs), 0.5 * (u.squaredNorm() - vs.squaredNorm()), 1e-9);
    }
  }
}

TEST(WaveVariables, SignConventions) {
  const double b = 10.0, s = std::sqrt(2.0 * b);
  const Vector3d u(1.0, -2.0, 0.5);
  Vector3d xdot, v, fport;
  // unmatched slave in free space (no force): total reflection v = u, moves at sqrt(2/b) u
  pv::wave_slave(b, false, u, Vector3d::Zero(), xdot, v, fport);
  EXPECT_NEAR((v - u).norm(), 0.0, 1e-12);
  EXPECT_NEAR((xdot - s / b * u).norm(), 0.0, 1e-12);
  // matched slave in free space: nothing comes back; it moves at u / sqrt(2b)
  pv::wave_slave(b, true, u, Vector3d::Zero(), xdot, v, fport);
  EXPECT_NEAR(v.norm(), 0.0, 1e-12);
  EXPECT_NEAR((xdot - u / s).norm(), 0.0, 1e-12);
  // a rigid wall (the port does not move): v = -u
  Vector3d uu, vv;
  pv::wave_encode(b, Vector3d::Zero(), Vector3d(0, 0, 3.0), uu, vv);
  EXPECT_NEAR((vv + uu).norm(), 0.0, 1e-12);

  // the loop's signs: the tool presses down (-z) on a floor, the contact force on it is +z;
  // the slave returns v = f_e / sqrt(2b) > 0 (matched), the master at rest renders +z: the
  // operator is pushed out of the floor, with the contact force's magnitude
  const Vector3d f_contact(0.0, 0.0, 4.0);
  pv::wave_slave(b, true, Vector3d::Zero(), -f_contact, xdot, v, fport);
  EXPECT_GT(v.z(), 0.0);
  Vector3d fm, um;
  pv::wave_master(b, Vector3d::Zero(), v, fm, um);
  const Vector3d device_force = -fm;
  EXPECT_NEAR(device_force.z(), 4.0, 1e-12);
  // and a master moving in free space (nothing returned) feels the damping b
  pv::wave_master(b, Vector3d(0.1, 0, 0), Vector3d::Zero(), fm, um);
  EXPECT_NEAR(-fm.x(), -b * 0.1, 1e-12);
}

TEST(WaveVariables, ReceiverNeverUsesMoreEnergyThanSentAndCatchesUpAfterLoss) {
  // a sender at 1 kHz; every 7th sample is lost and samples 300-340 are lost in one burst
  pv::WaveSender tx;
  pv::WaveReceiver rx;
  const double dt = 1e-3;
  Vector3d used_direct = Vector3d::Zero();
  Vector3d last_int = Vector3d::Zero(), last_e = Vector3d::Zero();
  for (int k = 1; k <= 2000; ++k) {
    const double t = k * dt;
    const Vector3d w(std::sin(9.0 * t), 0.5 * std::cos(3.0 * t), k < 1000 ? 1.0 : 0.0);
    tx.add(w, dt);
    const bool lost = k % 7 == 0 || (k >= 300 && k <= 340);
    if (!lost) {
      last_int = tx.integral;
      last_e = tx.energy_j;
    }
    used_direct = rx.receive(last_int, last_e, dt, 1e9);
    for (int i = 0; i < 3; ++i) ASSERT_LE(rx.used_energy_j()[i], last_e[i] + 1e-12) << k;
  }
  // after the sender went quiet on z, all of its integral has been replayed: no drift
  EXPECT_NEAR(rx.used_integral().z(), tx.integral.z(), 1e-9);
  EXPECT_NEAR(rx.used_integral().x(), tx.integral.x(), 2e-3);
  EXPECT_TRUE(used_direct.allFinite());
}

/// A constant-delay line of `d` samples.
template <class T>
class DelayLine {
 public:
  explicit DelayLine(int d) : buf_(static_cast<std::size_t>(d) + 1) {}
  T push_pop(const T& in) {
    buf_[head_] = in;
    head_ = (head_ + 1) % buf_.size();
    return buf_[head_];  // the oldest (d samples ago)
  }

 private:
  std::vector<T> buf_;
  std::size_t head_ = 0;
};

struct WaveSample {
  Vector3d integral = Vector3d::Zero(), energy = Vector3d::Zero();
  bool valid = false;
};

TEST(WaveVariables, ChannelEnergyStaysNonNegativeForConstantDelays) {
  // master and slave ports with the library's transforms, joined by constant delays; the
  // energy that entered the channel at the master port minus what left at the slave port,
  // from the ports' power variables, must never be negative
  for (int delay_ms : {0, 10, 50, 200}) {
    for (double filter_hz : {0.0, 10.0}) {
      const double dt = 1e-3, b = 10.0;
      pv::WaveMasterPort master;
      master.configure(b, 1e9, filter_hz);
      master.reset(Vector3d::Zero());
      pv::WaveSlavePort slave;
      slave.configure(b, true, 1e9);
      slave.reset();
      DelayLine<WaveSample> fwd(delay_ms), bwd(delay_ms);
      WaveSample at_slave, at_master;
      Vector3d x = Vector3d::Zero();
      double e_in = 0.0, e_out = 0.0, e_min = 0.0, e_peak = 0.0, identity_err = 0.0;
      Vector3d slave_force_env = Vector3d::Zero();
      for (int k = 1; k <= 20000; ++k) {
        const double t = k * dt;
        // the operator: three sines per axis (0.02 m); x integrates xdot exactly
        Vector3d xdot;
        for (int i = 0; i < 3; ++i) {
          xdot[i] = 0.02 * (2 * M_PI * 0.7 * std::cos(2 * M_PI * 0.7 * t + i) +
                            2 * M_PI * 1.9 * std::cos(2 * M_PI * 1.9 * t + 2 * i) +
                            2 * M_PI * 4.3 * std::cos(2 * M_PI * 4.3 * t + 3 * i));
        }
        x += dt * xdot;
        master.update(x, xdot, at_master.integral, at_master.energy, at_master.valid, dt);
        e_in += dt * master.force_n().dot(xdot);
        identity_err = std::max(
            identity_err, std::fabs(master.force_n().dot(xdot) -
                                    0.5 * (master.u().squaredNorm() - master.v().squaredNorm())));
        WaveSample out{master.sent().integral, master.sent().energy_j, true};
        at_slave = fwd.push_pop(out);
        if (at_slave.valid) {
          // the slave's environment: a stiff floor at z = -0.01 m under the commanded point
          slave.update(at_slave.integral, at_slave.energy, Vector3d::Zero(), slave_force_env, dt);
          e_out += dt * slave.port_force_n().dot(slave.velocity_mps());
          const double pen = -0.01 - slave.position_m().z();
          slave_force_env = Vector3d(0, 0, pen > 0.0 ? 5000.0 * pen : 0.0);
        }
        WaveSample back{slave.sent().integral, slave.sent().energy_j, slave.started()};
        at_master = bwd.push_pop(back);
        e_min = std::min(e_min, e_in - e_out);
        e_peak = std::max(e_peak, e_in);
      }
      SCOPED_TRACE(testing::Message() << delay_ms << " ms, filter " << filter_hz << " Hz");
      EXPECT_GE(e_min, -1e-9) << "channel generated energy";
      EXPECT_GT(e_peak, 0.1);  // a real exchange went through
      EXPECT_LT(identity_err, 1e-9);
      // the slave followed the master: position after the delay (free motion most of the time)
      EXPECT_GT(slave.dissipated_j(), 0.0);
    }
  }
}

TEST(WaveVariables, StableAt200msOnAStiffWallWherePositionPositionIsNot) {
  // the press-slip task against the stiff wall (k = 2e4 N/m), K_ps = 3000 N/m, 200 ms each way
  for (double wall_k : {2.0e4, 3000.0}) {
    SCOPED_TRACE(wall_k);
    PressScenario pp = scenario("position-position", Environment::kWall, wall_k, 3000.0, 0.2);
    const PressSetup pp_setup = build_press_setup(pp);
    ASSERT_FALSE(task_stable_at(press_loop_model(pp, pp_setup), 0.2)) << "theory: unstable";
    EXPECT_EQ(run(pp_setup).verdict, Verdict::kUnstable);

    PressScenario wave = pp;
    wave.scheme = "wave-variables";
    const RunResult r = run(build_press_setup(wave));
    EXPECT_EQ(r.verdict, Verdict::kStable) << r.reason;
    EXPECT_FALSE(r.cut);
    EXPECT_LE(r.max_force_n, 10.0 + 1e-9);
    EXPECT_GT(r.contact_s, 2.0);         // it pressed the wall
    EXPECT_LT(r.final_error_m, 1.0e-3);  // and the tool is back with the master
  }
}

TEST(WaveVariables, NoDriftUnderLossJitterAndBurstLoss) {
  PressScenario s = scenario("wave-variables", Environment::kSphere, 2000, 400, 0.05);
  s.jitter_s = 0.005;
  PressSetup setup = build_press_setup(s);
  setup.loop.forward.loss_probability = 0.05;
  setup.loop.backward.loss_probability = 0.05;
  setup.loop.forward.burst_loss = true;
  setup.loop.forward.burst_p_good_to_bad = 0.01;
  setup.loop.forward.burst_p_bad_to_good = 0.2;
  const RunResult r = run(setup);
  EXPECT_EQ(r.verdict, Verdict::kStable) << r.reason;
  EXPECT_GT(r.contact_s, 2.0);
  EXPECT_LT(r.final_error_m, 1.0e-3);
}

TEST(WaveVariables, MatchedTerminationAbsorbsTheEchoOfFreeMotion) {
  // a quick 4 cm move in free space, then still: unmatched, the wave bounces between the
  // slave (free space reflects v = u) and the device every round trip
  double after_rms[2] = {0.0, 0.0};
  for (int matched = 0; matched < 2; ++matched) {
    PressScenario s = scenario("wave-variables", Environment::kSphere, 2000, 400, 0.1);
    s.wave_matched = matched == 1;
    PressSetup setup = build_press_setup(s);
    setup.device.script.kind = ScriptKind::kStep;
    setup.device.script.start_m = Vector3d(0.0, 0.0, 0.05);
    setup.device.script.step_m = Vector3d(0.04, 0.0, 0.0);
    setup.device.script.step_time_s = 0.3;
    setup.device.script.tremor_amplitude_m = 0.0;
    setup.loop.duration_s = 2.0;
    SimulatedDevice dev(setup.device);
    teleop::server::WorldSlave slave(teleop::test::press_world(setup));
    LoopbackSession session(setup.loop, dev, slave);
    session.start();
    double sum = 0.0;
    int n = 0;
    while (session.step()) {
      if (session.time_s() > 0.6 && session.time_s() < 1.6) {
        sum += session.device_force_n().squaredNorm();
        ++n;
      }
    }
    after_rms[matched] = std::sqrt(sum / n);
    EXPECT_EQ(session.metrics().verdict(), Verdict::kStable);
  }
  EXPECT_GT(after_rms[0], 0.5);   // the echo: the operator's own motion, felt again
  EXPECT_LT(after_rms[1], 0.05);  // absorbed
}

TEST(WaveVariables, BadWaveNeverReachesThePhysicsAndIsCounted) {
  teleop::server::WorldSlave slave(
      teleop::sim::tool_world_model(teleop::sim::ToolModel{}, Vector3d(0, 0, 0.6)));
  SlaveCommand c;
  c.scheme = SchemeId::kWaveVariables;
  c.passivity_session = 7;
  c.wave.impedance_ns_per_m = 10.0;
  c.position_m = Vector3d(0, 0, 0.6);
  for (int i = 1; i <= 50; ++i) {
    c.seq = static_cast<std::uint64_t>(i);
    c.wave.u_integral = Vector3d(0, 0, -1e-3 * i);
    c.wave.u_energy_j = Vector3d(0, 0, 1e-4 * i);
    slave.step(c, 1e-3);
  }
  ASSERT_EQ(slave.port().rejected(), 0u);
  const Vector3d before = slave.sample().position_m;
  const auto hold_steps = [&](const SlaveCommand& bad) {
    for (int i = 0; i < 20; ++i) slave.step(bad, 1e-3);
  };
  SlaveCommand nan = c;
  nan.seq = 51;
  nan.wave.u_integral.x() = std::nan("");
  hold_steps(nan);
  SlaveCommand negative = c;
  negative.seq = 52;
  negative.wave.u_energy_j.z() = -1.0;
  hold_steps(negative);
  SlaveCommand bad_b = c;
  bad_b.seq = 53;
  bad_b.wave.impedance_ns_per_m = 0.0;
  hold_steps(bad_b);
  SlaveCommand stale = c;  // an older cumulative energy within the same session
  stale.seq = 54;
  stale.wave.u_energy_j = Vector3d(0, 0, 1e-4);
  hold_steps(stale);
  EXPECT_EQ(slave.port().rejected(), 80u);
  EXPECT_TRUE(slave.sample().position_m.allFinite());
  EXPECT_LT((slave.sample().position_m - before).norm(), 2e-3);  // held
  EXPECT_TRUE(slave.sample().wave.v_integral.allFinite());
  // a good command afterwards is used again
  c.seq = 60;
  c.wave.u_integral = Vector3d(0, 0, -0.06);
  c.wave.u_energy_j = Vector3d(0, 0, 0.01);
  slave.step(c, 1e-3);
  EXPECT_EQ(slave.port().rejected(), 80u);
}

TEST(WaveVariables, TheInProcessSlaveIsTheSlavePortThenTheToolLaw) {
  // the in-process slave (the server's cycle) against the port and the tool law written out
  const teleop::sim::ToolModel tm = teleop::test::wall_tool();
  teleop::sim::ToolState ts = teleop::sim::tool_state_at(Vector3d(0, 0, 0.56));
  teleop::server::WorldSlave mine(teleop::sim::tool_world_model(tm, ts.position_m));
  pv::SlavePassivityPort port;
  bool touched = false;
  for (SchemeId scheme : {SchemeId::kWaveVariables, SchemeId::kTimeDomainPassivity}) {
    pv::WaveSender tx;
    for (int i = 1; i <= 3000; ++i) {
      SlaveCommand c;
      c.seq = static_cast<std::uint64_t>(i);
      c.scheme = scheme;
      c.passivity_session = scheme == SchemeId::kWaveVariables ? 1u : 2u;
      c.wave.impedance_ns_per_m = 10.0;
      const Vector3d vel(0.02 * std::cos(0.004 * i), 0.0, -0.03 * std::sin(0.002 * i));
      tx.add(std::sqrt(20.0) * vel, 1e-3);
      c.velocity_mps = vel;
      c.position_m = Vector3d(0.0, 0.0, 0.56) + Vector3d(0.005 * std::sin(0.004 * i), 0.0,
                                                         0.015 * (std::cos(0.002 * i) - 1.0));
      c.wave.u_integral = tx.integral;
      c.wave.u_energy_j = tx.energy_j;
      c.tdpa.energy_in_j = 0.02 * i * 1e-3;
      mine.step(c, 1e-3);
      pv::SlavePortState st{ts.position_m, ts.velocity_mps, ts.contact_force_n};
      const pv::SlavePortTarget t = port.before_step(
          pv::port_command(c), st, pv::TrackingGains{tm.kp_n_per_m, tm.kd_ns_per_m}, 1e-3);
      teleop::sim::ToolInput in;
      in.target_position_m = t.position_m;
      in.target_velocity_mps = t.velocity_mps;
      in.hold = t.hold;
      teleop::sim::tool_step(tm, ts, in, 1e-3);
      port.after_step(ts.tracking_force_n, 1e-3);
      ASSERT_NEAR((mine.sample().position_m - ts.position_m).norm(), 0.0, 1e-9) << i;
      ASSERT_NEAR((mine.sample().wave.v_integral - port.report().wave.v_integral).norm(), 0.0,
                  1e-9);
      ASSERT_NEAR(mine.sample().tdpa.energy_out_j, port.report().tdpa.energy_out_j, 1e-12);
      touched |= mine.sample().in_contact;
    }
  }
  EXPECT_TRUE(touched);
  EXPECT_GT(port.report().tdpa.energy_out_j, 0.0);
}

// --- configuration --------------------------------------------------------------------------

TEST(Passivity, BadConfigNamesFileFieldValueAndRange) {
  using teleop::test::config_error_of;
  const auto yaml_error = [](const std::string& text) {
    return config_error_of([&] {
      controller_params_from_yaml(
          teleop::config::Node::parse(text, "master.yaml").at("controller"));
    });
  };
  std::string m = yaml_error("controller: {scheme: wave-variables, wave_impedance_ns_per_m: -3}");
  EXPECT_NE(m.find("master.yaml"), std::string::npos) << m;
  EXPECT_NE(m.find("controller.wave_impedance_ns_per_m"), std::string::npos) << m;
  EXPECT_NE(m.find("-3"), std::string::npos) << m;
  EXPECT_NE(m.find("[0, 10000]"), std::string::npos) << m;
  m = yaml_error("controller: {scheme: wave-variables, wave_filter_hz: 5000}");
  EXPECT_NE(m.find("controller.wave_filter_hz"), std::string::npos) << m;
  EXPECT_NE(m.find("5000"), std::string::npos) << m;
  EXPECT_NE(m.find("[0, 1000]"), std::string::npos) << m;
  m = yaml_error("controller: {scheme: tdpa, tdpa_base: wave}");
  EXPECT_NE(m.find("controller.tdpa_base"), std::string::npos) << m;
  EXPECT_NE(m.find("position-position"), std::string::npos) << m;
  m = yaml_error("controller: {scheme: waves}");
  EXPECT_NE(m.find("wave-variables"), std::string::npos) << m;
  EXPECT_NE(m.find("tdpa"), std::string::npos) << m;
  m = yaml_error("controller: {scheme: tdpa, tdpa_drift: 3}");
  EXPECT_NE(m.find("tdpa_drift"), std::string::npos) << m;
  // a derived b out of range (K_ps = 0) is named with its inputs when configured
  m = config_error_of([] {
    ControllerParams p;
    p.scheme = "wave-variables";
    p.slave_stiffness_n_per_m = 0.0;
    make_controller(p.scheme)->configure(p, DeviceSpec{});
  });
  EXPECT_NE(m.find("wave impedance"), std::string::npos) << m;
  EXPECT_NE(m.find("slave_stiffness_n_per_m = 0"), std::string::npos) << m;
  EXPECT_NE(m.find("[0.01, 20]"), std::string::npos) << m;
  m = config_error_of([] {
    ControllerParams p;
    p.wave_time_constant_s = 3.0;
    p.validate();
  });
  EXPECT_NE(m.find("wave_time_constant_s = 3"), std::string::npos) << m;
  // good values load
  const ControllerParams ok = controller_params_from_yaml(teleop::config::Node::parse(
      "{scheme: wave-variables, wave_impedance_ns_per_m: 6, wave_matched: false, "
      "wave_filter_hz: 0}"));
  EXPECT_EQ(ok.scheme, "wave-variables");
  EXPECT_DOUBLE_EQ(ok.wave_impedance_ns_per_m, 6.0);
  EXPECT_FALSE(ok.wave_matched);
}

TEST(Passivity, WaveImpedanceDefaultIsDerivedFromTheSlaveAndClampedToTheDevice) {
  ControllerParams p;
  p.scheme = "wave-variables";
  WaveVariablesController c;
  c.configure(p, DeviceSpec{});
  EXPECT_DOUBLE_EQ(c.wave_impedance_ns_per_m(), 400.0 * 0.025);  // K_ps tau_b
  p.slave_stiffness_n_per_m = 3000.0;  // 75 N s/m wanted, the device renders at most 20
  c.configure(p, DeviceSpec{});
  EXPECT_DOUBLE_EQ(c.wave_impedance_ns_per_m(), 20.0);
  p.workspace.position_scale = 2.0;  // rendered damping alpha beta b
  c.configure(p, DeviceSpec{});
  EXPECT_DOUBLE_EQ(c.wave_impedance_ns_per_m(), 10.0);
  p.wave_impedance_ns_per_m = 4.0;
  c.configure(p, DeviceSpec{});
  EXPECT_DOUBLE_EQ(c.wave_impedance_ns_per_m(), 4.0);
}

// --- time-domain passivity ------------------------------------------------------------------

TEST(Tdpa, ObserversNeverGoBelowToleranceOnceTheControllerActs) {
  // position-position, K = 3000 N/m, stiff wall, 100 ms each way: without the passivity
  // controllers the network generates energy; with them, both observers and the network's
  // energy stay at or above zero (to the slave's one-sample force prediction)
  constexpr double kTol = 1e-6;  // [J]
  for (const char* scheme : {"position-position", "tdpa"}) {
    PressScenario s = scenario(scheme, Environment::kWall, 2.0e4, 3000.0, 0.1);
    s.safety = false;  // let the loop run as it is
    const PressSetup setup = build_press_setup(s);
    SimulatedDevice dev(setup.device);
    teleop::server::WorldSlave slave(teleop::test::press_world(setup));
    LoopbackSession session(setup.loop, dev, slave);
    session.start();
    // the network's energy from the ports' power variables: -F_m . v_m at the master, and
    // -f_c . v_c at the slave (v_c the rate of the command handed to the PD)
    double e_net = 0.0, e_net_min = 0.0, w_m_min = 0.0, w_s_min = 0.0;
    Vector3d x_cmd_prev = Vector3d::Zero();
    bool first = true;
    while (session.step()) {
      const double dt = 1e-3;
      e_net -= dt * session.controller_force_n().dot(session.last_sample().master_velocity_mps);
      const Vector3d x_cmd =
          slave.port().tdpa().started() && std::string(scheme) == "tdpa"
              ? Vector3d(slave.port().tdpa().drift_m() + session.slave_command().position_m)
              : session.slave_command().position_m;
      if (!first && session.slave_command().enabled) {
        e_net -= slave.tracking_force_n().dot((x_cmd - x_cmd_prev) / dt) * dt;
      }
      first = false;
      x_cmd_prev = x_cmd;
      e_net_min = std::min(e_net_min, e_net);
      if (std::string(scheme) == "tdpa") {
        w_m_min = std::min(w_m_min, session.controller().passivity_status().observer_j);
        w_s_min = std::min(
            w_s_min, session.slave_command().tdpa.energy_in_j - slave.sample().tdpa.energy_out_j);
      }
    }
    SCOPED_TRACE(scheme);
    if (std::string(scheme) == "position-position") {
      EXPECT_LT(e_net_min, -0.05) << "without the PC the network generates energy";
      EXPECT_EQ(session.metrics().verdict(), Verdict::kUnstable);
    } else {
      EXPECT_GE(w_m_min, -kTol);
      EXPECT_GE(w_s_min, -kTol);
      EXPECT_GE(e_net_min, -kTol);
      const auto* c = dynamic_cast<const TimeDomainPassivityController*>(&session.controller());
      ASSERT_NE(c, nullptr);
      EXPECT_GT(c->pc().energy().dissipated_j, 0.01);          // the master PC acted
      EXPECT_GT(slave.sample().passivity_dissipated_j, 0.01);  // and the slave PC
      EXPECT_GE(session.metrics().energy_min_j(), -kTol);      // passive at the operator too
    }
  }
}

TEST(Tdpa, StabilisesPositionPositionAtK3000And100ms) {
  // theory: position-position at K = 3000 N/m has a 7 ms margin; at 100 ms it is unstable
  // holding still in free space and pressing the wall. With TDPA both are stable.
  // (Moving fast with this gain over 0.2 s of round trip means K 2T v of drag, which
  // saturates the device: passivity does not make that transparent; see docs/control.md.)
  PressScenario pp = scenario("position-position", Environment::kWall, 2.0e4, 3000.0, 0.1);
  ASSERT_LT(task_delay_margin(press_loop_model(pp, build_press_setup(pp))).one_way_s, 0.01);
  struct Case {
    const char* what;
    double start_z, end_z;
  };
  for (const Case& k : {Case{"free space", 0.05, 0.05}, Case{"wall, 1 mm in", 0.02, -0.001}}) {
    SCOPED_TRACE(k.what);
    const RunResult plain = run(hold_setup(pp, k.start_z, k.end_z, 3.0, 8.0));
    EXPECT_EQ(plain.verdict, Verdict::kUnstable);
    PressScenario tdpa = pp;
    tdpa.scheme = "tdpa";
    const RunResult r = run(hold_setup(tdpa, k.start_z, k.end_z, 3.0, 8.0));
    EXPECT_EQ(r.verdict, Verdict::kStable) << r.reason;
    EXPECT_FALSE(r.cut);
    EXPECT_LT(r.final_error_m, 1.5e-3);
  }
  // force-position, K_f = 2 (margin 11 ms): the wall press is unstable; on TDPA it is stable
  PressScenario fp = scenario("force-position", Environment::kWall, 2.0e4, 2.0, 0.1);
  EXPECT_EQ(run(hold_setup(fp, 0.02, -0.008, 3.0, 8.0)).verdict, Verdict::kUnstable);
  fp.scheme = "tdpa";
  fp.tdpa_base = "force-position";
  const RunResult r = run(hold_setup(fp, 0.02, -0.008, 3.0, 8.0));
  EXPECT_EQ(r.verdict, Verdict::kStable) << r.reason;
  EXPECT_GT(r.contact_s, 3.0);
}

TEST(Tdpa, PressTaskAtTheDefaultGainIsStableAtEveryDelay) {
  for (double d : {0.05, 0.1, 0.2}) {
    for (Environment env : {Environment::kSphere, Environment::kWall}) {
      PressScenario s = scenario("tdpa", env, env == Environment::kWall ? 2.0e4 : 2000.0, 400, d);
      const PressResult r = teleop::test::run_press_world(s);
      EXPECT_FALSE(r.analytic_stable) << d;  // the base loop alone is not
      if (d <= 0.1) {
        EXPECT_EQ(r.verdict, Verdict::kStable) << d << " " << r.reason;
      } else {
        // passive, never unstable; at 200 ms its drag (K 2T v) holds the device above its
        // continuous rating for longer than the spec allows, and the verdict says so
        EXPECT_EQ(r.verdict, Verdict::kOutOfSpec) << d << " " << r.reason;
      }
      EXPECT_GT(r.contact_time_s, 2.0);
    }
  }
}

TEST(Tdpa, MasterControllerDissipatesExactlyTheExcessAndNeverMoreThanTheForce) {
  pv::ImpedancePassivityController pc;
  const double dt = 1e-3;
  // no remote input yet: a force pushing along the velocity is reduced to zero power
  const Vector3d v(0.1, 0.0, 0.0), f(2.0, 1.0, 0.0);
  Vector3d out = pc.filter(f, v, 0.0, dt);
  EXPECT_NEAR(out.dot(v), 0.0, 1e-15);
  EXPECT_NEAR(out.y(), 1.0, 1e-15);  // the component across the motion stays
  EXPECT_LE((out - f).norm(), f.norm());
  pc.commit(out, f, v, dt);
  // with 1e-4 J received, dT f'.v may use exactly that
  out = pc.filter(f, v, 1e-4, dt);
  EXPECT_NEAR(dt * out.dot(v), 1e-4, 1e-15);
  pc.commit(out, f, v, dt);
  EXPECT_NEAR(pc.energy().out_j, 1e-4, 1e-15);
  // a force resisting the motion is input, untouched
  const Vector3d resist(-3.0, 0.0, 0.0);
  EXPECT_EQ(pc.filter(resist, v, 0.0, dt), resist);
}

TEST(Tdpa, SlaveControllerMeetsTheBudgetExactlyWithTheModelledTrackingLaw) {
  pv::AdmittancePassivityController pc;
  pc.configure(0.5);
  pc.reset();
  const double kp = 3000.0, kd = 12.0, dt = 1e-3;
  Vector3d xs(0, 0, 0), vs(0, 0, 0), x, v;
  double received = 0.0;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> d(-1.0, 1.0);
  Vector3d xc(0, 0, 0);
  for (int k = 0; k < 5000; ++k) {
    xc += Vector3d(d(rng), d(rng), d(rng)) * 2e-4;
    if (k % 10 == 0) received += 1e-5;  // a trickle of master input energy
    pc.filter(xc, received, xs, vs, kp, kd, dt, x, v);
    const Vector3d f = kp * (x - xs) + kd * (v - vs);
    pc.commit(f, dt);
    ASSERT_LE(pc.energy().out_j, received + 1e-12) << k;
    // a unit mass follows
    vs += dt * f;
    xs += dt * vs;
  }
  EXPECT_GT(pc.energy().dissipated_j, 0.0);
  EXPECT_GT(pc.drift_m().norm(), 0.0);  // the price: the command lags the master
}

// --- real time ------------------------------------------------------------------------------

TEST(Passivity, HotPathsAllocateNothing) {
  for (const char* scheme : {"wave-variables", "tdpa"}) {
    PressScenario s = scenario(scheme, Environment::kSphere, 2000, 0.0, 0.05);
    s.jitter_s = 0.002;
    const PressSetup setup = build_press_setup(s);
    SimulatedDevice dev(setup.device);
    teleop::server::WorldSlave slave(teleop::test::press_world(setup));
    LoopbackSession session(setup.loop, dev, slave);
    session.start();
    for (int i = 0; i < 100; ++i) session.step();  // warm up
    pv::SlavePassivityPort port;
    teleop::test::NoAllocScope scope;
    for (int i = 0; i < 3000; ++i) {
      session.step();
      const pv::SlavePortTarget t = port.before_step(
          pv::port_command(session.slave_command()),
          pv::SlavePortState{slave.sample().position_m, slave.sample().velocity_mps,
                             slave.sample().contact_force_n},
          pv::TrackingGains{}, 1e-3);
      port.after_step(slave.tracking_force_n() + 0.0 * t.position_m, 1e-3);
    }
    EXPECT_EQ(scope.allocations(), 0u) << scheme;
  }
}

TEST(Passivity, IdlCarriesTheNewFields) {
  SlaveCommand c;
  c.seq = 9;
  c.scheme = SchemeId::kWaveVariables;
  c.passivity_session = 77;
  c.wave.impedance_ns_per_m = 12.5;
  c.wave.matched = false;
  c.wave.u_integral = Vector3d(1, 2, 3);
  c.wave.u_energy_j = Vector3d(4, 5, 6);
  c.tdpa.energy_in_j = 0.25;
  teleop::MasterCommand m;
  to_idl(c, 1, m);
  EXPECT_EQ(m.passivity_session(), 77u);
  EXPECT_EQ(m.wave_impedance_ns_per_m(), 12.5);
  EXPECT_FALSE(m.wave_matched());
  EXPECT_EQ(m.wave_u_integral()[2], 3.0);
  EXPECT_EQ(m.wave_u_energy_j()[0], 4.0);
  EXPECT_EQ(m.tdpa_energy_in_j(), 0.25);
  EXPECT_EQ(m.scheme(), teleop::SCHEME_WAVE_VARIABLES);

  teleop::SlaveState st;
  st.tip_orientation_wxyz({1.0, 0.0, 0.0, 0.0});
  st.passivity_session(77);
  st.wave_v_integral({0.1, 0.2, 0.3});
  st.wave_v_energy_j({0.4, 0.5, 0.6});
  st.tdpa_energy_in_j(1.5);
  st.tdpa_energy_out_j(1.25);
  st.passivity_dissipated_j(0.125);
  SlaveSample s = from_idl(st);
  EXPECT_TRUE(s.valid);
  EXPECT_EQ(s.passivity_session, 77u);
  EXPECT_EQ(s.wave.v_energy_j.y(), 0.5);
  EXPECT_EQ(s.tdpa.energy_out_j, 1.25);
  st.wave_v_integral({0.0, std::nan(""), 0.0});
  EXPECT_FALSE(from_idl(st).valid);  // a non-finite backward wave is dropped at the edge
}

}  // namespace
