#include "client/metrics/hertz_reference.hpp"

#include <gtest/gtest.h>

namespace {

using teleop::master::hertz_line;
using teleop::master::hertz_reference;

TEST(HertzReference, TheProjectBallAtFiveMillimetres) {
  // the foam ball (E 6000 Pa, nu 0.3, 2 kg, radius 0.25 m) on the floor under its weight,
  // pressed 5 mm by the 0.05 m tip: 0.542 N (the validation's Hertz row)
  const auto h = hertz_reference(6000.0, 0.3, 0.25, 0.05, 2.0 * 9.81, 0.005);
  ASSERT_TRUE(h.valid);
  EXPECT_NEAR(h.force_n, 0.5422, 0.001);
  EXPECT_NEAR(h.secant_n_per_m, h.force_n / 0.005, 1e-9);
  EXPECT_GT(h.tangent_n_per_m, h.secant_n_per_m);  // F grows faster than linearly
  const std::string line = hertz_line(h, h.tangent_n_per_m);
  EXPECT_NE(line.find("5.0 mm"), std::string::npos) << line;
  EXPECT_NE(line.find("1.00 x the tangent"), std::string::npos) << line;
}

TEST(HertzReference, NoMaterialOrNoContactGivesNoLine) {
  EXPECT_FALSE(hertz_reference(0.0, 0.3, 0.25, 0.05, 19.6, 0.005).valid);
  EXPECT_FALSE(hertz_reference(6000.0, 0.5, 0.25, 0.05, 19.6, 0.005).valid);
  EXPECT_FALSE(hertz_reference(6000.0, 0.3, 0.25, 0.05, 19.6, 0.0).valid);
  EXPECT_EQ(hertz_line(hertz_reference(6000.0, 0.3, 0.25, 0.05, 19.6, 0.0), 100.0), "");
}

}  // namespace
