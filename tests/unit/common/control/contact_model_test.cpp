// The local contact model of the model-mediated scheme (common/control/contact_model.hpp): the
// geometry's surfaces, and the online estimate of stiffness, damping and offset.
#include "common/control/contact_model.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "tests/support/alloc_counter.hpp"

namespace teleop::mmt {
namespace {

TEST(ContactModel, PlaneAndSpherePriorsAreTheTipCentresHalfSpaces) {
  const SurfacePrior floor =
      plane_prior(100, Eigen::Vector3d::UnitZ(), 0.0, 0.05, Eigen::Vector3d(0, 0, 0.3), 2e4, 50);
  EXPECT_DOUBLE_EQ(floor.offset_m, 0.05);
  EXPECT_DOUBLE_EQ(floor.distance_m, 0.25);
  const SurfacePrior ball = sphere_prior(10, Eigen::Vector3d(0, 0, 0.25), 0.25, 0.05,
                                         Eigen::Vector3d(0.3, 0, 0.25 + 0.4), 300, 1);
  EXPECT_NEAR(ball.normal.dot(Eigen::Vector3d(0.6, 0, 0.8)), 1.0, 1e-12);
  EXPECT_NEAR(ball.distance_m, 0.5 - 0.3, 1e-12);
  EXPECT_NEAR(ball.offset_m - ball.normal.dot(Eigen::Vector3d(0.3, 0, 0.65)), -0.2, 1e-12);
  EXPECT_EQ(nearer(floor, ball).object_id, 10);
  LocalModel m;
  m.valid = true;
  m.offset_m = 0.05;
  m.stiffness_n_per_m = 1000;
  m.damping_ns_per_m = 10;
  EXPECT_NEAR(m.force_n(Eigen::Vector3d(0, 0, 0.04), Eigen::Vector3d(0, 0, -0.1)).z(), 11.0, 1e-9);
  // pulling out: the damper does not pull the tip back in
  EXPECT_NEAR(m.force_n(Eigen::Vector3d(0, 0, 0.04), Eigen::Vector3d(0, 0, 0.1)).z(), 10.0, 1e-9);
  EXPECT_EQ(m.force_n(Eigen::Vector3d(0, 0, 0.06), Eigen::Vector3d::Zero()).norm(), 0.0);
  EXPECT_NEAR(m.energy_j(Eigen::Vector3d(0, 0, 0.04)), 0.05, 1e-12);
}

TEST(ContactModel, EstimatesStiffnessDampingAndOffsetOfASpringFromItsResponse) {
  // a surface at z = 0.30 (tip centre), k = 800 N/m, b = 8 N s/m, nominal (prior) 300 N/m:
  // the tip presses in and out sinusoidally, 1-3 mm deep, at 1 kHz
  ContactEstimator e;
  const SurfacePrior prior =
      plane_prior(7, Eigen::Vector3d::UnitZ(), 0.25, 0.05, Eigen::Vector3d(0, 0, 0.31), 300, 1);
  const double k = 800.0, b = 8.0, dt = 1e-3;
  teleop::test::NoAllocScope scope;
  for (int i = 0; i < 3000; ++i) {
    const double t = i * dt;
    const double z = 0.30 - 0.002 - 0.001 * std::sin(2 * M_PI * 2.0 * t);
    const double vz = -0.001 * 2 * M_PI * 2.0 * std::cos(2 * M_PI * 2.0 * t);
    const double f = k * (0.30 - z) + b * std::max(0.0, -vz);
    e.update(Eigen::Vector3d(0.01, 0, z), Eigen::Vector3d(0, 0, vz), Eigen::Vector3d(0, 0, f), true,
             prior);
  }
  EXPECT_EQ(scope.allocations(), 0u);
  const LocalModel& m = e.model();
  ASSERT_TRUE(m.valid);
  EXPECT_TRUE(m.touched);
  EXPECT_EQ(m.object_id, 7);
  EXPECT_NEAR(m.stiffness_n_per_m, k, 0.03 * k);
  EXPECT_NEAR(m.offset_m, 0.30, 1e-4);
  // compression-only damping fitted by a linear term: about half of b, and never negative
  EXPECT_GT(m.damping_ns_per_m, 0.0);
  EXPECT_LT(m.damping_ns_per_m, b);
  // out of contact the geometry comes back, with what was learnt of this object
  e.update(Eigen::Vector3d(0.01, 0, 0.32), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), false,
           prior);
  EXPECT_TRUE(e.model().valid);
  EXPECT_FALSE(e.model().touched);
  EXPECT_DOUBLE_EQ(e.model().offset_m, 0.30);
  EXPECT_NEAR(e.model().stiffness_n_per_m, k, 0.03 * k);
  // far from every surface: no model
  const SurfacePrior far =
      plane_prior(7, Eigen::Vector3d::UnitZ(), 0.25, 0.05, Eigen::Vector3d(0, 0, 0.9), 300, 1);
  e.update(Eigen::Vector3d(0, 0, 0.9), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), false,
           far);
  EXPECT_FALSE(e.model().valid);
}

}  // namespace
}  // namespace teleop::mmt
