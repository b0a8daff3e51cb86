// The vendor SDK driver skeleton (client/device/vendor/vendor_sdk_device.cpp), compiled against
// a simulated OpenHaptics device (tests/vendor/fake_openhaptics: the HD API subset it calls) and
// run: the spec it declares from the SDK, the 1 kHz servo callback exchanging position and force
// with the haptic loop, saturation to the declared peak force, a device fault, no device, zero
// force on deactivation, and the master's gains clamped to what the device declared.
#include "client/device/vendor/vendor_sdk_device.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <thread>

#include "client/control/bilateral_controller.hpp"
#include "common/config/config.hpp"
#include "fake_hd.hpp"

namespace teleop::master {
namespace {

void wait_ticks(std::uint64_t n) {
  const std::uint64_t until = fake_hd::ticks() + n;
  for (int i = 0; i < 5000 && fake_hd::ticks() < until; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

TEST(VendorSdkDevice, DeclaresItsSpecFromTheSdkInSiUnits) {
  fake_hd::reset();
  VendorSdkDevice dev("");
  dev.configure();
  const DeviceSpec& s = dev.spec();
  EXPECT_EQ(s.name, "vendor: Fake Touch");
  EXPECT_TRUE(s.workspace_min_m.isApprox(Eigen::Vector3d(-0.08, -0.06, -0.035)));
  EXPECT_TRUE(s.workspace_max_m.isApprox(Eigen::Vector3d(0.08, 0.06, 0.035)));
  EXPECT_DOUBLE_EQ(s.max_force_n, 3.3);
  EXPECT_DOUBLE_EQ(s.max_continuous_force_n, 0.88);
  EXPECT_NEAR(s.max_stiffness_n_per_m, 1260.0, 1e-9);  // 1.26 N/mm
  EXPECT_NEAR(s.max_damping_ns_per_m, 2.5, 1e-12);     // 0.0025 N s/mm
  EXPECT_EQ(dev.state(), DeviceLifecycle::kInactive);
}

TEST(VendorSdkDevice, TheServoCallbackExchangesPositionAndSaturatedForce) {
  fake_hd::reset();
  VendorSdkDevice dev("");
  dev.activate();
  ASSERT_TRUE(fake_hd::scheduler_running());
  const double p[3] = {10.0, -20.0, 5.0}, v[3] = {100.0, 0.0, -50.0};
  fake_hd::set_handle(p, v, 1);
  wait_ticks(20);
  const DeviceReading r = dev.read();
  ASSERT_TRUE(r.valid);
  EXPECT_TRUE(r.position_m.isApprox(Eigen::Vector3d(0.010, -0.020, 0.005)));
  EXPECT_TRUE(r.linear_velocity_mps.isApprox(Eigen::Vector3d(0.1, 0.0, -0.05)));
  EXPECT_EQ(r.buttons, 1u);

  dev.write(Eigen::Vector3d(1.0, 0.0, -0.5), Eigen::Vector3d::Zero());
  wait_ticks(20);
  double f[3];
  bool enabled = false;
  fake_hd::last_force(f, enabled);
  EXPECT_TRUE(enabled);
  EXPECT_DOUBLE_EQ(f[0], 1.0);
  EXPECT_DOUBLE_EQ(f[2], -0.5);
  dev.write(Eigen::Vector3d(10.0, 0.0, 0.0), Eigen::Vector3d::Zero());  // beyond the 3.3 N peak
  wait_ticks(20);
  fake_hd::last_force(f, enabled);
  EXPECT_NEAR(f[0], 3.3, 1e-12);

  // about 1 kHz: the scheduler's own ticks over 200 ms of wall time
  const std::uint64_t t0 = fake_hd::ticks();
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_GT(fake_hd::ticks() - t0, 100u);

  dev.deactivate();
  EXPECT_FALSE(fake_hd::scheduler_running());
  fake_hd::last_force(f, enabled);
  EXPECT_FALSE(enabled);
  EXPECT_EQ(f[0], 0.0);
  EXPECT_FALSE(dev.read().valid);
}

TEST(VendorSdkDevice, WhenTheHapticLoopStopsWritingTheServoFadesTheForceAtTheRateBound) {
  fake_hd::reset();
  VendorSdkDevice dev("");
  dev.activate();
  const double step_n = dev.spec().max_force_rate_n_per_s * kServoPeriodS;
  dev.write(Eigen::Vector3d(3.0, 0.0, 0.0), Eigen::Vector3d::Zero());
  // the force rises at the bound: sampled with the tick count, never faster than it
  double prev = 0.0;
  std::uint64_t prev_tick = fake_hd::ticks();
  double f[3];
  bool enabled = false;
  for (int i = 0; i < 20; ++i) {
    wait_ticks(1);
    const std::uint64_t t = fake_hd::ticks();
    fake_hd::last_force(f, enabled);
    // one tick of slack: the counter and the force are read apart
    EXPECT_LE(std::abs(f[0] - prev), step_n * static_cast<double>(t - prev_tick + 1) + 1e-12);
    prev = f[0];
    prev_tick = t;
  }
  EXPECT_GT(prev, 0.0);
  // the loop stops writing (a stall): the servo holds while the command is fresh, then fades out
  dev.write(Eigen::Vector3d(3.0, 0.0, 0.0), Eigen::Vector3d::Zero());
  const std::uint64_t written = fake_hd::ticks();
  wait_ticks(static_cast<std::uint64_t>(kServoStaleTicks) / 5);
  fake_hd::last_force(f, enabled);
  // (checked only when this thread was not held up past the staleness limit meanwhile)
  if (fake_hd::ticks() - written + 1 < static_cast<std::uint64_t>(kServoStaleTicks)) {
    EXPECT_DOUBLE_EQ(f[0], 3.0);
  }
  wait_ticks(static_cast<std::uint64_t>(kServoStaleTicks) + 20);
  fake_hd::last_force(f, enabled);
  EXPECT_TRUE(enabled);
  EXPECT_EQ(f[0], 0.0);
  // a new force from the loop is rendered again
  dev.write(Eigen::Vector3d(0.5, 0.0, 0.0), Eigen::Vector3d::Zero());
  const std::uint64_t again = fake_hd::ticks();
  wait_ticks(5);
  fake_hd::last_force(f, enabled);
  if (fake_hd::ticks() - again + 1 < static_cast<std::uint64_t>(kServoStaleTicks)) {
    EXPECT_DOUBLE_EQ(f[0], 0.5);
  }
  dev.deactivate();
}

TEST(VendorSdkDevice, ADeviceFaultMakesTheReadingInvalid) {
  fake_hd::reset();
  VendorSdkDevice dev("");
  dev.activate();
  wait_ticks(10);
  EXPECT_TRUE(dev.read().valid);
  fake_hd::set_fault(true);
  wait_ticks(10);
  EXPECT_FALSE(dev.read().valid);  // the master holds: no reading, no force rendered
  fake_hd::set_fault(false);
  wait_ticks(10);
  EXPECT_TRUE(dev.read().valid);
  dev.deactivate();
}

TEST(VendorSdkDevice, NoDeviceIsAClearConfigurationError) {
  fake_hd::reset();
  fake_hd::fail_next_init();
  VendorSdkDevice dev("Default Device");
  try {
    dev.configure();
    FAIL() << "configure() should have thrown";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("--device vendor: cannot open the device: no device "
                                         "found (fake)"),
              std::string::npos)
        << e.what();
  }
}

TEST(VendorSdkDevice, TheMasterClampsItsGainsToWhatTheDeviceDeclared) {
  fake_hd::reset();
  VendorSdkDevice dev("");
  dev.configure();
  ControllerParams p;
  p.scheme = "position-position";
  p.master_stiffness_n_per_m = 3000.0;
  p.master_damping_ns_per_m = 10.0;
  auto c = make_controller(p.scheme);
  c->configure(p, dev.spec());
  EXPECT_NEAR(c->master_stiffness_n_per_m(), 1260.0, 1e-9);
  EXPECT_NEAR(c->master_damping_ns_per_m(), 2.5, 1e-12);
  EXPECT_NEAR(c->force_limit_n(), 3.3, 1e-12);
}

}  // namespace
}  // namespace teleop::master
