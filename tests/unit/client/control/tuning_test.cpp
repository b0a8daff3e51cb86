// Live tuning's rules (client/control/tuning.hpp): which fields each scheme takes, the bounds
// and the messages of a rejection, and the ramp's path.
#include "client/control/tuning.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "client/control/scheme_traits.hpp"
#include "tests/support/config_error.hpp"

namespace teleop::master {
namespace {

TuningLimits limits_for(const std::string& scheme) {
  ControllerParams p;
  p.scheme = scheme;
  return tuning_limits(p, DeviceSpec{}, 4096, 1e-3);
}

TEST(Tuning, EachSchemeTakesTheGainsItUses) {
  const std::uint32_t delays = kTuneForwardDelay | kTuneBackwardDelay;
  EXPECT_EQ(limits_for("position-position").tunable,
            kTuneMasterStiffness | kTuneMasterDamping | kTuneSlaveStiffness | delays);
  EXPECT_EQ(limits_for("force-position").tunable,
            kTuneForceGain | kTuneMasterDamping | kTuneSlaveStiffness | delays);
  EXPECT_EQ(limits_for("wave-variables").tunable, kTuneMasterDamping | delays);
  EXPECT_EQ(limits_for("model-mediated").tunable,
            kTuneMasterDamping | kTuneSlaveStiffness | delays);
  ControllerParams tdpa;
  tdpa.scheme = "tdpa";
  tdpa.tdpa_base = "force-position";
  EXPECT_TRUE(tunable_fields(tdpa) & kTuneForceGain);
  EXPECT_FALSE(tunable_fields(tdpa) & kTuneMasterStiffness);
}

TEST(Tuning, TheGainsAreTheSchemesTraitsAndAnUnknownSchemeIsRefused) {
  const std::uint32_t delays = kTuneForwardDelay | kTuneBackwardDelay;
  for (const std::string& label : scheme_variant_labels()) {
    ControllerParams p;
    apply_scheme_variant(label, p);
    EXPECT_EQ(tunable_fields(p), scheme_traits(p).tunable_gains | delays) << label;
  }
  ControllerParams p;
  p.scheme = "pp";
  EXPECT_NE(test::config_error_of([&] { tunable_fields(p); }).find("scheme 'pp' is unknown"),
            std::string::npos);
}

TEST(Tuning, BoundsComeFromTheDeviceAndTheChannel) {
  const TuningLimits l = limits_for("position-position");
  EXPECT_DOUBLE_EQ(l.max_master_stiffness_n_per_m, DeviceSpec{}.max_stiffness_n_per_m);
  EXPECT_DOUBLE_EQ(l.max_master_damping_ns_per_m, DeviceSpec{}.max_damping_ns_per_m);
  EXPECT_DOUBLE_EQ(l.max_delay_s, 2.0);  // 4096 slots at 1 kHz hold 4 s: capped at 2 s
  ControllerParams p;
  EXPECT_NEAR(tuning_limits(p, DeviceSpec{}, 1000, 1e-3).max_delay_s, 0.8, 1e-12);
}

TEST(Tuning, ARejectionNamesTheFieldTheValueAndTheRange) {
  const TuningLimits l = limits_for("position-position");
  TuningRequestData r;
  EXPECT_EQ(check_tuning(r, l, "position-position"), "the request sets no field");
  r.fields = kTuneMasterStiffness;
  r.values.master_stiffness_n_per_m = 5000.0;
  EXPECT_EQ(check_tuning(r, l, "position-position"),
            "master_stiffness_n_per_m = 5000 is outside [0, 3000] N/m");
  r.values.master_stiffness_n_per_m = -1.0;
  EXPECT_NE(check_tuning(r, l, "position-position").find("= -1 is outside"), std::string::npos);
  r.values.master_stiffness_n_per_m = 1000.0;
  EXPECT_EQ(check_tuning(r, l, "position-position"), "");
  r.fields = kTuneForwardDelay;
  r.values.forward_delay_s = 2.5;
  EXPECT_EQ(check_tuning(r, l, "position-position"),
            "forward_delay_ms = 2500 is outside [0, 2000] ms");
  r.values.forward_delay_s = std::numeric_limits<double>::infinity();
  EXPECT_NE(check_tuning(r, l, "position-position").find("forward_delay_ms = inf"),
            std::string::npos);
  r.values.forward_delay_s = 0.1;
  r.ramp_s = std::nan("");
  EXPECT_NE(check_tuning(r, l, "position-position").find("ramp_s = nan"), std::string::npos);
  r.ramp_s = 0.5;
  r.fields = 64;
  EXPECT_EQ(check_tuning(r, l, "position-position"), "unknown field bits 64");
  r.fields = kTuneForceGain;
  EXPECT_EQ(check_tuning(r, l, "position-position"),
            "force_gain is not used by the position-position scheme");
}

TEST(Tuning, TheRampIsLinearAndADelaySlewsAtItsOwnRate) {
  TuningValues v;
  v.force_gain = 1.0;
  TuningRamp ramp;
  ramp.reset(v);
  EXPECT_FALSE(ramp.advance(0.0));
  TuningRequestData r;
  r.fields = kTuneForceGain | kTuneForwardDelay;
  r.values.force_gain = 3.0;
  r.values.forward_delay_s = 0.2;  // 0.8 s at 0.25 s/s
  r.ramp_s = 0.01;                 // raised to the 0.05 s minimum
  ramp.start(r, 10.0, 0.05);
  ASSERT_TRUE(ramp.advance(10.025));
  EXPECT_NEAR(ramp.current().force_gain, 2.0, 1e-12);
  EXPECT_NEAR(ramp.current().forward_delay_s, 0.2 * 0.025 / 0.8, 1e-12);
  ramp.advance(10.4);
  EXPECT_DOUBLE_EQ(ramp.current().force_gain, 3.0);
  EXPECT_NEAR(ramp.current().forward_delay_s, 0.1, 1e-12);
  EXPECT_TRUE(ramp.active());
  ramp.advance(10.8);
  EXPECT_FALSE(ramp.active());
  EXPECT_DOUBLE_EQ(ramp.current().forward_delay_s, 0.2);
  EXPECT_EQ(
      describe_tuning(r, v, 0.05),
      "force_gain 1 -> 3, forward_delay_ms 0 -> 200 over 0.05 s (a delay moves at most 250 ms "
      "per s)");
}

}  // namespace
}  // namespace teleop::master
