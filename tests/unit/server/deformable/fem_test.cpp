// The volumetric model (model fem): rest data, the co-rotated force law, contacts, integrators.
// Its agreement with physics (Hertz, Lamb, an independent FEM) is tested in
// validation_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "server/deformable/deformable.hpp"
#include "tests/support/alloc_counter.hpp"

namespace df = teleop::sim::deformable;

namespace {

df::DeformableParams fem_params(int level, df::IntegratorKind integrator) {
  df::DeformableParams p;
  p.model = df::ModelKind::kFem;
  p.integrator = integrator;
  p.level = level;
  p.radius_m = 0.25;
  p.centre_m = Eigen::Vector3d(0, 0, 0.25);
  p.youngs_modulus_pa = 6000.0;
  p.poisson_ratio = 0.3;
  p.mass_kg = 2.0;
  p.stiffness_damping_s = 1e-4;
  p.mass_damping_per_s = 5.0;
  p.sleep_time_s = 1e9;
  return p;
}

Eigen::Matrix3d rotation(double angle) {
  return Eigen::AngleAxisd(angle, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
}

}  // namespace

TEST(Fem, ModelHasTheMeshTheMassAndTheMaterial) {
  const df::DeformableParams p = fem_params(1, df::IntegratorKind::kSymplecticEuler);
  const df::DeformableModel m = df::make_model(p);
  EXPECT_EQ(m.node_count, m.mesh.vertex_count());
  EXPECT_GT(m.fem.node_count, m.node_count);  // interior nodes follow the surface ones
  EXPECT_EQ(m.state_node_count(), m.fem.node_count);
  EXPECT_NEAR(m.fem.mass_kg.sum(), 2.0, 1e-12);
  EXPECT_NEAR(m.total_mass_kg, 2.0, 1e-12);
  EXPECT_NEAR(m.lame_mu_pa, 6000.0 / 2.6, 1e-9);
  EXPECT_NEAR(m.lame_lambda_pa, 6000.0 * 0.3 / (1.3 * 0.4), 1e-9);
  EXPECT_NEAR(m.rest_centre_m.z(), 0.25, 2e-3);
  // contact springs: pressure stiffness times node area
  EXPECT_NEAR(m.contact_k.sum(), m.fem.pressure_stiffness_pa_per_m * m.area_m2.sum(), 1e-6);
  const df::DeformableState s = df::make_state(m);
  EXPECT_EQ(s.x.cols(), m.fem.node_count);
  EXPECT_EQ(s.f_ext.cols(), m.fem.node_count);
  // a surface model cannot take a tet mesh, nor the fem model a triangle mesh
  df::DeformableParams ms;
  EXPECT_THROW(df::make_model(df::make_tet_mesh_for(p), ms), teleop::config::ConfigError);
  EXPECT_THROW(df::make_model(df::make_mesh_for(ms), p), teleop::config::ConfigError);
}

TEST(Fem, RigidMotionMakesNoForceAndForcesAreTheEnergyGradient) {
  for (bool nodal : {false, true}) {
    SCOPED_TRACE(nodal ? "nodal pressure" : "element strain");
    df::DeformableParams params = fem_params(1, df::IntegratorKind::kSymplecticEuler);
    params.nodal_pressure = nodal;
    const df::DeformableModel m = df::make_model(params);
    df::DeformableState s = df::make_state(m);
    // rotated by 0.9 rad and moved: no elastic force (co-rotation), no energy
    const Eigen::Matrix3d r = rotation(0.9);
    for (int i = 0; i < m.fem.node_count; ++i) {
      s.x.col(i) = r * m.fem.rest.col(i) + Eigen::Vector3d(0.3, -0.2, 0.1);
    }
    Eigen::Matrix3Xd f;
    df::internal_forces(m, s, f);
    EXPECT_LT(f.cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT(df::elastic_energy(m, s), 1e-12);
    // a deformed state: the force is minus the gradient of the energy (central differences)
    for (int i = 0; i < m.fem.node_count; ++i) {
      const Eigen::Vector3d p = m.fem.rest.col(i);
      s.x.col(i) = rotation(0.4) * (p + 0.05 * Eigen::Vector3d(std::sin(9 * p.z()), p.x() * p.y(),
                                                               std::cos(7 * p.x()) * 0.3));
    }
    df::internal_forces(m, s, f);
    const double h = 1e-7;
    double worst = 0.0, scale = f.cwiseAbs().maxCoeff();
    Eigen::Matrix3Xd scratch;
    for (int i : {0, 5, m.node_count + 3}) {
      for (int c = 0; c < 3; ++c) {
        df::DeformableState t = s;
        t.x(c, i) += h;
        df::internal_forces(m, t, scratch);
        const double ep = df::elastic_energy(m, t);
        t.x(c, i) -= 2 * h;
        df::internal_forces(m, t, scratch);
        const double em = df::elastic_energy(m, t);
        worst = std::max(worst, std::fabs(-(ep - em) / (2 * h) - f(c, i)));
      }
    }
    EXPECT_GT(scale, 1e-3);
    EXPECT_LT(worst, 1e-4 * scale);
  }
}

TEST(Fem, FallsFreelyAtGAndKeepsItsShape) {
  for (auto integ : {df::IntegratorKind::kSymplecticEuler, df::IntegratorKind::kImplicitEuler}) {
    SCOPED_TRACE(df::to_string(integ));
    df::DeformableParams p = fem_params(1, integ);
    const df::DeformableModel m = df::make_model(p);
    df::DeformableState s = df::make_state(m);
    const Eigen::Vector3d c0 = df::centroid(m, s);
    for (int k = 0; k < 200; ++k) ASSERT_EQ(df::step(m, s, 1e-3, nullptr), df::StepStatus::kOk);
    const double t = 0.2;
    EXPECT_NEAR(df::centroid(m, s).z(), c0.z() - 0.5 * 9.81 * t * t, 2e-3);
    EXPECT_LT(df::elastic_energy(m, s), 1e-9);
  }
}

TEST(Fem, RestsOnTheFloorCarryingItsWeightAndStaysStable) {
  for (auto integ : {df::IntegratorKind::kSymplecticEuler, df::IntegratorKind::kImplicitEuler}) {
    SCOPED_TRACE(df::to_string(integ));
    df::DeformableParams p = fem_params(1, integ);
    teleop::sim::Plane floor;
    const df::DeformableModel m = df::make_model(p, {floor});
    df::DeformableState s = df::make_state(m);
    teleop::sim::EventQueue events;
    // dropped undeformed, it bounces on its own elasticity while it sags; over whole bounces
    // the floor carries the weight
    double impulse = 0.0, lowest = 0.0;
    for (int k = 0; k < 2000; ++k) {
      ASSERT_EQ(df::step(m, s, 1e-3, &events), df::StepStatus::kOk) << k;
      if (k >= 1000) {
        impulse += s.plane_force_n.z() * 1e-3;
        lowest = std::min(lowest, s.x.row(2).minCoeff());
      }
    }
    EXPECT_NEAR(impulse / 1.0, 2.0 * 9.81, 0.05 * 2.0 * 9.81);
    EXPECT_LT(lowest, 0.0);      // pressed into the floor a little
    EXPECT_GT(lowest, -0.5e-3);  // by a stiff contact
    EXPECT_EQ(s.fault_count, 0u);
  }
  // with stiffness damping (implicit Euler: stable at any damping) it comes to rest
  df::DeformableParams p = fem_params(1, df::IntegratorKind::kImplicitEuler);
  p.stiffness_damping_s = 0.02;
  teleop::sim::Plane floor;
  const df::DeformableModel m = df::make_model(p, {floor});
  df::DeformableState s = df::make_state(m);
  for (int k = 0; k < 1500; ++k) ASSERT_EQ(df::step(m, s, 1e-3, nullptr), df::StepStatus::kOk);
  EXPECT_LT(df::kinetic_energy(m, s), 1e-5);
  EXPECT_NEAR(s.plane_force_n.z(), 2.0 * 9.81, 0.01 * 2.0 * 9.81);
}

TEST(Fem, BallDroppedOnTheFloorSettles) {
  // the drag acts relative to the floor while the ball rests on it, so the bounce of its centre
  // on its own elasticity dies out with the default damping (beta alone barely damps it)
  const df::DeformableParams p = fem_params(1, df::IntegratorKind::kSymplecticEuler);
  teleop::sim::Plane floor;
  const df::DeformableModel m = df::make_model(p, {floor});
  df::DeformableState s = df::make_state(m);
  double early = 0.0, late = 0.0;
  for (int k = 0; k < 2500; ++k) {
    ASSERT_EQ(df::step(m, s, 1e-3, nullptr), df::StepStatus::kOk) << k;
    const double fastest = s.v.colwise().norm().maxCoeff();
    if (k < 500) early = std::max(early, fastest);
    if (k >= 2400) late = std::max(late, fastest);
  }
  EXPECT_GT(early, 0.3);  // it was bouncing (about 0.5 m/s)
  EXPECT_LT(late, 0.02);  // and is still
  EXPECT_NEAR(s.plane_force_n.z(), 2.0 * 9.81, 0.02 * 2.0 * 9.81);
}

TEST(Fem, TheTipSphereIsKeptOutAndFeelsTheReaction) {
  df::DeformableParams p = fem_params(2, df::IntegratorKind::kSymplecticEuler);
  p.gravity_mps2.setZero();
  p.mass_damping_per_s = 30.0;
  df::DeformableModel m = df::make_model(p);
  df::DeformableState s = df::make_state(m);
  // hold the bottom cap; press the top with the 0.05 m sphere by 5 mm
  for (int i = 0; i < m.fem.node_count; ++i) {
    if (m.fem.rest(2, i) < 0.02) {
      s.pinned[static_cast<std::size_t>(i)] = 1;
      s.pin_target.col(i) = m.fem.rest.col(i);
    }
  }
  const double r = 0.05, top = 0.5;
  Eigen::Vector3d c(0, 0, top + r);
  s.tip_radius_m = r;
  for (int k = 0; k < 1500; ++k) {
    const Eigen::Vector3d next(0, 0, top + r - std::min(5e-3, 1e-5 * k));
    s.tip_from_m = c;
    s.tip_to_m = next;
    s.tip_velocity_mps = (next - c) / 1e-3;
    c = next;
    ASSERT_EQ(df::step(m, s, 1e-3, nullptr), df::StepStatus::kOk);
  }
  EXPECT_GT(s.tip_node_count, 3);
  EXPECT_GT(s.tip_force_n.z(), 0.05);  // the body pushes the tip up
  EXPECT_LT(std::fabs(s.tip_force_n.x()) + std::fabs(s.tip_force_n.y()), 0.05 * s.tip_force_n.z());
  EXPECT_LT(s.tip_depth_m, 0.2e-3);  // nodes barely inside the sphere: a stiff contact
}

// The ratio of the tangential to the normal force on the tip sphere while it slides along x at
// 20 mm/s over the top of a ball held at its bottom cap, pressed 5 mm in (zero gravity), with
// tip friction (mu_s, mu_k); the mean over the last 0.2 s of 0.4 s of sliding.
double sliding_force_ratio(df::IntegratorKind integ, double mu_s, double mu_k) {
  df::DeformableParams p = fem_params(2, integ);
  p.gravity_mps2.setZero();
  p.mass_damping_per_s = 30.0;
  const df::DeformableModel m = df::make_model(p);
  df::DeformableState s = df::make_state(m);
  for (int i = 0; i < m.fem.node_count; ++i) {
    if (m.fem.rest(2, i) < 0.02) {
      s.pinned[static_cast<std::size_t>(i)] = 1;
      s.pin_target.col(i) = m.fem.rest.col(i);
    }
  }
  s.tip_friction_static = mu_s;
  s.tip_friction_kinetic = mu_k;
  const double r = 0.05, top = 0.5, h = 1e-3;
  Eigen::Vector3d c(0, 0, top + r);
  s.tip_radius_m = r;
  double fx = 0.0, fz = 0.0;
  for (int k = 0; k < 650; ++k) {
    Eigen::Vector3d next(0, 0, top + r - std::min(5e-3, 2e-5 * k));
    if (k >= 250) next.x() = 0.02 * h * (k - 249);
    s.tip_from_m = c;
    s.tip_to_m = next;
    s.tip_velocity_mps = (next - c) / h;
    c = next;
    EXPECT_EQ(df::step(m, s, h, nullptr), df::StepStatus::kOk) << k;
    if (k >= 450) {
      fx += s.tip_force_n.x();
      fz += s.tip_force_n.z();
    }
  }
  EXPECT_EQ(s.fault_count, 0u);
  return -fx / fz;  // the force on the tip opposes its motion along +x
}

TEST(Fem, TheTipSlidingOverTheBallFeelsCoulombFriction) {
  for (auto integ : {df::IntegratorKind::kSymplecticEuler, df::IntegratorKind::kImplicitEuler}) {
    SCOPED_TRACE(df::to_string(integ));
    const double frictionless = sliding_force_ratio(integ, 0.0, 0.0);
    const double sliding = sliding_force_ratio(integ, 0.3, 0.24);
    std::printf(
        "%s: tangential / normal force on the sliding tip: %.4f frictionless, %.4f with "
        "mu_s 0.3, mu_k 0.24\n",
        df::to_string(integ), frictionless, sliding);
    // frictionless: only the tilt of the contact normal over the curved top (a few degrees)
    EXPECT_LT(std::fabs(frictionless), 0.06);
    // sliding: the kinetic coefficient, never more than the static one
    EXPECT_GT(sliding, 0.24 * 0.85);
    EXPECT_LT(sliding, 0.3);
  }
}

TEST(Fem, StableStepEstimateIsBelowItsBoundAndStepsAllocateNothing) {
  for (auto integ : {df::IntegratorKind::kSymplecticEuler, df::IntegratorKind::kExplicitEuler,
                     df::IntegratorKind::kImplicitEuler}) {
    for (bool nodal : {false, true}) {
      SCOPED_TRACE(std::string(df::to_string(integ)) + (nodal ? " nodal pressure" : ""));
      df::DeformableParams p = fem_params(1, integ);
      p.nodal_pressure = nodal;
      teleop::sim::Plane floor;
      const df::DeformableModel m = df::make_model(p, {floor});
      EXPECT_GT(m.omega_max_rad_per_s, 0.0);
      EXPECT_LE(m.omega_max_rad_per_s, m.omega_bound_rad_per_s * (1 + 1e-9));
      if (integ == df::IntegratorKind::kImplicitEuler) {
        EXPECT_TRUE(std::isinf(m.stable_step_s));
      } else {
        EXPECT_GT(m.stable_step_s, 0.0);
      }
      df::DeformableState s = df::make_state(m);
      teleop::sim::EventQueue events;
      s.tip_radius_m = 0.05;
      s.tip_from_m = s.tip_to_m = Eigen::Vector3d(0, 0, 0.545);
      s.f_ext.col(3) = Eigen::Vector3d(0.1, 0, 0);
      s.pinned[static_cast<std::size_t>(m.node_count + 1)] = 1;
      s.pin_target.col(m.node_count + 1) = s.x.col(m.node_count + 1);
      df::step(m, s, 1e-3, &events);  // warm-up: the sub-step event
      teleop::test::NoAllocScope scope;
      for (int k = 0; k < 20; ++k) df::step(m, s, 1e-3, &events);
      EXPECT_EQ(scope.allocations(), 0u);
      EXPECT_EQ(s.fault_count, 0u);
    }
  }
}

TEST(Fem, MassScalingAddsInertiaWhereTheStepIsLimitedAndKeepsTheWeight) {
  df::DeformableParams p = fem_params(2, df::IntegratorKind::kSymplecticEuler);
  const df::DeformableModel plain = df::make_model(p);
  ASSERT_LT(plain.stable_step_s, 0.5e-3);  // 4 sub-steps of 1 ms unscaled
  p.mass_scaling_step_s = 1e-3;
  teleop::sim::Plane floor;
  const df::DeformableModel m = df::make_model(p, {floor});
  EXPECT_GE(m.stable_step_s, 1e-3);
  EXPECT_EQ(m.substeps_for(1e-3), 1);
  // the fewest grams: below 2 % of the mass, on a minority of the nodes, never less than before
  EXPECT_GT(m.fem.added_mass_kg, 0.0);
  EXPECT_LT(m.fem.added_mass_kg, 0.02 * p.mass_kg);
  EXPECT_NEAR(m.fem.mass_kg.sum() - m.fem.weight_kg.sum(), m.fem.added_mass_kg, 1e-12);
  int raised = 0;
  for (int i = 0; i < m.fem.node_count; ++i) {
    EXPECT_GE(m.fem.mass_kg(i), m.fem.weight_kg(i));
    raised += m.fem.mass_kg(i) > m.fem.weight_kg(i);
  }
  EXPECT_GT(raised, 0);
  EXPECT_LT(raised, m.fem.node_count / 2);
  EXPECT_NEAR(m.fem.weight_kg.sum(), p.mass_kg, 1e-9);
  EXPECT_EQ(m.fem.weight_kg, plain.fem.mass_kg);
  // its weight on the floor is the physical one, its centroid the physical centroid
  df::DeformableState s = df::make_state(m);
  EXPECT_NEAR((df::centroid(m, s) - p.centre_m).norm(),
              (df::centroid(plain, s) - p.centre_m).norm(), 1e-12);
  double impulse = 0.0;
  for (int k = 0; k < 2000; ++k) {
    ASSERT_EQ(df::step(m, s, 1e-3, nullptr), df::StepStatus::kOk) << k;
    if (k >= 1000) impulse += s.plane_force_n.z() * 1e-3;
  }
  EXPECT_NEAR(impulse, 2.0 * 9.81, 0.05 * 2.0 * 9.81);
  EXPECT_EQ(s.fault_count, 0u);
  // a target it cannot reach within the allowed fraction is an error naming the fields
  p.mass_scaling_max_fraction = 1e-4;
  try {
    df::make_model(p);
    ADD_FAILURE() << "no ConfigError";
  } catch (const teleop::config::ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("mass_scaling_step_s"), std::string::npos) << what;
    EXPECT_NE(what.find("mass_scaling_max_fraction"), std::string::npos) << what;
  }
}
