// The deformable models against physics (server/world/physics_validation.hpp): the references
// themselves, then the volumetric FEM against Lamb's vibrations, Hertz contact and the weight.
// The full table (every model, mesh and material) is `teleop_experiment validate`.
#include "server/world/physics_validation.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace df = teleop::sim::deformable;
namespace va = teleop::sim::validation;

namespace {

double error_pct(double value, double reference) { return 100.0 * (value / reference - 1.0); }

}  // namespace

TEST(PhysicsReferences, LambRootsMatchThePublishedValues) {
  EXPECT_NEAR(va::lamb_eta(va::LambMode::kT2, 0.3), 2.5011, 2e-4);
  EXPECT_NEAR(va::lamb_eta(va::LambMode::kT2, 0.45), 2.5011, 2e-4);  // any nu
  // the breathing mode's closed form against the tabulated roots (REFERENCE: 4.440 / 4.996 /
  // 5.790 / 7.095 / 10.005 at nu 0.25 ... 0.45)
  const double nus[] = {0.25, 0.30, 0.35, 0.40, 0.45};
  const double s0[] = {4.440, 4.996, 5.790, 7.095, 10.005};
  for (int k = 0; k < 5; ++k) {
    EXPECT_NEAR(va::lamb_eta(va::LambMode::kS0, nus[k]), s0[k], 2e-3 * s0[k]) << nus[k];
  }
  EXPECT_NEAR(va::lamb_eta(va::LambMode::kS2, 0.30), 2.646, 1e-12);
  EXPECT_NEAR(va::lamb_eta(va::LambMode::kS2, 0.325), 2.649, 1e-12);
  EXPECT_THROW(va::lamb_eta(va::LambMode::kS2, 0.1), std::domain_error);
  // the foam ball: c_T = sqrt(E / (2 rho (1 + nu)))
  const va::Material foam = va::foam();
  EXPECT_NEAR(foam.density_kg_per_m3 * 4.0 / 3.0 * M_PI * std::pow(0.25, 3), 2.0, 1e-12);
  const double ct = std::sqrt(6000.0 / (2.0 * foam.density_kg_per_m3 * 1.3));
  EXPECT_NEAR(va::lamb_frequency_hz(va::LambMode::kT2, foam, 0.25), 2.5011 * ct / (2 * M_PI * 0.25),
              1e-3);
}

TEST(PhysicsReferences, HertzTwoContactsInSeries) {
  const va::Material foam = va::foam();
  const double es = 6000.0 / (1.0 - 0.09);
  EXPECT_NEAR(va::contact_modulus_pa(foam), es, 1e-9);
  EXPECT_NEAR(va::hertz_depth_m(es, 0.1, va::hertz_force_n(es, 0.1, 3e-3)), 3e-3, 1e-15);
  // the travel is the sum of both indentations; the inverse finds the force back
  for (double preload : {0.0, 19.62}) {
    const double f = va::hertz_floor_force_n(foam, 0.25, 0.05, 5e-3, preload);
    EXPECT_NEAR(va::hertz_floor_travel_m(foam, 0.25, 0.05, f, preload), 5e-3, 1e-12);
    const double tip = va::hertz_depth_m(es, 1.0 / (1 / 0.05 + 1 / 0.25), f);
    EXPECT_LT(tip, 5e-3);  // the floor takes the rest
  }
  // a preloaded (flattened) floor contact is stiffer: more force for the same travel
  EXPECT_GT(va::hertz_floor_force_n(foam, 0.25, 0.05, 5e-3, 19.62),
            va::hertz_floor_force_n(foam, 0.25, 0.05, 5e-3, 0.0));
}

TEST(FemAgainstPhysics, LambFrequenciesWithinTenPercentAndConverging) {
  const va::Material foam = va::foam();
  for (auto mode : {va::LambMode::kS2, va::LambMode::kT2, va::LambMode::kS0}) {
    SCOPED_TRACE(va::to_string(mode));
    const double ref = va::lamb_frequency_hz(mode, foam, va::kBallRadiusM);
    double err[3] = {0, 0, 0};
    for (int level : {1, 2}) {
      const df::DeformableParams p =
          va::ball_params(df::ModelKind::kFem, df::IntegratorKind::kSymplecticEuler, level, foam);
      err[level] = error_pct(va::free_vibration_hz(p, mode, 1.0, ref), ref);
      EXPECT_LT(std::fabs(err[level]), 10.0) << "level " << level;  // measured 0.3-2.6 %
    }
    // T2 and S0 are below Lamb at level 1 and closer at level 2 (S2 is within 0.3 % at both)
    if (mode != va::LambMode::kS2) {
      EXPECT_LT(std::fabs(err[2]), std::fabs(err[1]));
    }
  }
}

TEST(FemAgainstPhysics, TipOnTheBallOnTheFloorApproachesHertzAsTheMeshIsRefined) {
  const va::Material foam = va::foam();
  const std::vector<double> travels = {5e-3, 10e-3};
  const double weight = 2.0 * 9.81;
  double worst[3] = {0, 0, 0};
  for (int level : {1, 2}) {
    const df::DeformableParams p =
        va::ball_params(df::ModelKind::kFem, df::IntegratorKind::kSymplecticEuler, level, foam);
    const va::PressResult r = va::press_ball(p, va::Support::kFloor, true, travels, 0.01, 1.0);
    EXPECT_EQ(r.faults, 0u);
    EXPECT_NEAR(r.floor_force_n, weight, 0.005 * weight);  // the floor carries the weight
    EXPECT_GT(r.sag_top_m, 0.015);                         // and the ball sags (23-24 mm)
    EXPECT_LT(r.sag_top_m, 0.035);
    for (std::size_t k = 0; k < travels.size(); ++k) {
      const double ref = va::hertz_floor_force_n(foam, 0.25, 0.05, travels[k], weight);
      const double e = error_pct(r.force_n[k], ref);
      EXPECT_GT(e, 0.0) << "level " << level;  // linear tetrahedra are too stiff, not too soft
      worst[level] = std::max(worst[level], std::fabs(e));
    }
  }
  // measured: level 1 24-27 %, level 2 14-17 % (level 3 11-12 %, teleop_experiment validate)
  EXPECT_LT(worst[2], worst[1]);
  EXPECT_LT(worst[2], 20.0);
}

TEST(FemAgainstPhysics, NodalPressureUnlocksANearlyIncompressibleBall) {
  // silicone, nu = 0.45: linear tetrahedra lock (too stiff); the average nodal pressure does not
  const va::Material rubber = va::silicone();
  const std::vector<double> travels = {2e-3, 5e-3, 10e-3};
  df::DeformableParams p =
      va::ball_params(df::ModelKind::kFem, df::IntegratorKind::kSymplecticEuler, 2, rubber);
  const double weight = p.mass_kg * 9.81;
  double worst[2] = {0, 0};
  for (bool nodal : {false, true}) {
    p.nodal_pressure = nodal;
    const va::PressResult r = va::press_ball(p, va::Support::kFloor, true, travels, 0.01, 1.0);
    EXPECT_EQ(r.faults, 0u);
    for (std::size_t k = 0; k < travels.size(); ++k) {
      const double ref = va::hertz_floor_force_n(rubber, 0.25, 0.05, travels[k], weight);
      worst[nodal] = std::max(worst[nodal], std::fabs(error_pct(r.force_n[k], ref)));
    }
  }
  // measured at level 2: element strain 18-27 %, nodal pressure 5-9 %
  EXPECT_GT(worst[0], 15.0);
  EXPECT_LT(worst[1], 10.0);
  // and its breathing mode stays within 10 % of Lamb (measured -8.5 %)
  const double ref = va::lamb_frequency_hz(va::LambMode::kS0, rubber, va::kBallRadiusM);
  EXPECT_LT(std::fabs(error_pct(va::free_vibration_hz(p, va::LambMode::kS0, 1.0, ref), ref)), 10.0);
}
