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
  const std::string line = hertz_line(h, h.tangent_n_per_m, h.secant_n_per_m);
  EXPECT_NE(line.find("5.0 mm"), std::string::npos) << line;
  EXPECT_NE(line.find("1.00 x the tangent"), std::string::npos) << line;
}

TEST(HertzReference, NoMaterialOrNoContactGivesNoLine) {
  EXPECT_FALSE(hertz_reference(0.0, 0.3, 0.25, 0.05, 19.6, 0.005).valid);
  EXPECT_FALSE(hertz_reference(6000.0, 0.5, 0.25, 0.05, 19.6, 0.005).valid);
  EXPECT_FALSE(hertz_reference(6000.0, 0.3, 0.25, 0.05, 19.6, 0.0).valid);
  EXPECT_EQ(hertz_line(hertz_reference(6000.0, 0.3, 0.25, 0.05, 19.6, 0.0), 100.0, 100.0), "");
}

TEST(HertzReference, TheLineFitOverTheLoadingPhaseLiesBetweenTheSecantAndTheTangent) {
  // without preload F = c x^1.5: the least-squares line over x in [0, X] has the slope
  // 12 (1/3.5 - 1/5) c X^0.5 = (36/35) F(X) / X, i.e. (24/35) of the tangent 1.5 F(X) / X
  const double X = 0.004;
  const auto h = hertz_reference(6000.0, 0.3, 0.25, 0.05, 0.0, X, 0.0, X);
  ASSERT_TRUE(h.valid);
  EXPECT_NEAR(h.fit_n_per_m, 36.0 / 35.0 * h.secant_n_per_m, 1e-3 * h.secant_n_per_m);
  EXPECT_NEAR(h.fit_n_per_m, 24.0 / 35.0 * h.tangent_n_per_m, 1e-3 * h.tangent_n_per_m);
  const std::string line = hertz_line(h, h.fit_n_per_m * 0.5, h.fit_n_per_m);
  EXPECT_NE(line.find("(0.0-4.0 mm)"), std::string::npos) << line;
  EXPECT_NE(line.find("stiffness felt 0.50 x, environment 1.00 x"), std::string::npos) << line;
  // under the weight's preload the curve is straighter: the fit is nearer the tangent
  const auto w = hertz_reference(6000.0, 0.3, 0.25, 0.05, 19.62, X, 0.0, X);
  EXPECT_GT(w.fit_n_per_m / w.tangent_n_per_m, h.fit_n_per_m / h.tangent_n_per_m);
  // no range, no fit
  EXPECT_EQ(hertz_reference(6000.0, 0.3, 0.25, 0.05, 19.62, X, 0.002, 0.001).fit_n_per_m, 0.0);
}

}  // namespace
