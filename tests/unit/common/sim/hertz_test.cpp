#include "common/sim/hertz.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace {

namespace hz = teleop::sim::hertz;

TEST(Hertz, OneContactFollowsTheThreeHalvesLawAndInverts) {
  const double es = hz::contact_modulus_pa(6000.0, 0.3);
  EXPECT_NEAR(es, 6000.0 / 0.91, 1e-9);
  const double f1 = hz::force_n(es, 0.25, 0.001), f4 = hz::force_n(es, 0.25, 0.004);
  EXPECT_NEAR(f4 / f1, 8.0, 1e-9);  // (4)^(3/2)
  EXPECT_NEAR(hz::depth_m(es, 0.25, f4), 0.004, 1e-12);
  EXPECT_EQ(hz::force_n(es, 0.25, -0.001), 0.0);
}

TEST(Hertz, TheTangentIsTheSlopeOfTheFloorForce) {
  const double es = hz::contact_modulus_pa(6000.0, 0.3);
  for (const double preload : {0.0, 19.62}) {
    for (const double d : {0.001, 0.005, 0.02}) {
      const double h = 1e-6;
      const double slope = (hz::floor_force_n(es, 0.25, 0.05, d + h, preload) -
                            hz::floor_force_n(es, 0.25, 0.05, d - h, preload)) /
                           (2.0 * h);
      EXPECT_NEAR(hz::floor_tangent_n_per_m(es, 0.25, 0.05, d, preload), slope, 1e-3 * slope)
          << "preload " << preload << " travel " << d;
      // two contacts in series are softer than the tip's alone; the weight's preload stiffens
      // the floor contact
      const double r_tip = 1.0 / (1.0 / 0.05 + 1.0 / 0.25);
      EXPECT_LT(hz::floor_force_n(es, 0.25, 0.05, d, preload), hz::force_n(es, r_tip, d));
    }
  }
  EXPECT_GT(hz::floor_force_n(es, 0.25, 0.05, 0.005, 19.62),
            hz::floor_force_n(es, 0.25, 0.05, 0.005, 0.0));
}

}  // namespace
