// The deformable body: parameters, model construction, integrators, stability limits,
// convergence order, contact, sleeping, faults and the no-allocation rule.
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <string>

#include "server/deformable/deformable.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/unit/server/deformable/test_helpers.hpp"

namespace {

using namespace teleop::sim::deformable;
using namespace teleop::sim::deformable::testing;
using teleop::config::ConfigError;
using teleop::config::Node;

const ModelKind kModels[] = {ModelKind::kMassSpring, ModelKind::kNavierLinear,
                             ModelKind::kNavierCorotational};
const IntegratorKind kIntegrators[] = {IntegratorKind::kExplicitEuler,
                                       IntegratorKind::kSymplecticEuler,
                                       IntegratorKind::kImplicitEuler};

// ---------------------------------------------------------------------------------------------
// parameters

TEST(Params, LoadsYamlAndConvertsMaterial) {
  const Node root = Node::parse(
      "deformable:\n"
      "  model: navier_corotational\n"
      "  integrator: implicit_euler\n"
      "  level: 2\n"
      "  radius_m: 0.1\n"
      "  centre_m: [0, 0, 0.1]\n"
      "  density_kg_per_m3: 100\n"
      "  youngs_modulus_pa: 2600\n"
      "  poisson_ratio: 0.3\n"
      "  gravity_mps2: [0, 0, 0]\n",
      "scene.yaml");
  const DeformableParams p = load_deformable_params(root.at("deformable"));
  EXPECT_EQ(p.model, ModelKind::kNavierCorotational);
  EXPECT_EQ(p.integrator, IntegratorKind::kImplicitEuler);
  EXPECT_EQ(p.level, 2);
  EXPECT_EQ(p.radial_stiffness_n_per_m3, 0.0);  // Navier default: no radial springs
  const DeformableModel m = build(p);
  EXPECT_NEAR(m.lame_mu_pa, 1000.0, 1e-9);
  EXPECT_NEAR(m.lame_lambda_pa, 2600.0 * 0.3 / (1.3 * 0.4), 1e-9);
  EXPECT_NEAR(m.density_kg_per_m3, 100.0, 1e-9);
  EXPECT_NEAR(m.total_mass_kg, 100.0 * m.volume_m3, 1e-12);
  EXPECT_FALSE(m.has_centre);
}

TEST(Params, ErrorsNameFileFieldAndRange) {
  auto expect_error = [](const std::string& yaml, const std::string& needle) {
    const Node root = Node::parse(yaml, "bad.yaml");
    try {
      load_deformable_params(root.at("deformable"));
      ADD_FAILURE() << "no ConfigError for: " << yaml;
    } catch (const ConfigError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("bad.yaml"), std::string::npos) << what;
      EXPECT_NE(what.find(needle), std::string::npos) << what;
    }
  };
  expect_error("deformable: {poisson_ratio: 0.5}", "deformable.poisson_ratio");
  expect_error("deformable: {level: 9}", "deformable.level");
  expect_error("deformable: {model: finite_elements}", "deformable.model");
  expect_error("deformable: {model: fem, level: 5}", "deformable.level");  // shipped balls 1-4
  expect_error("deformable: {model: mass_spring, tet_mesh_file: b.msh}", "tet_mesh_file");
  expect_error("deformable: {model: mass_spring, mass_scaling_step_s: 0.001}",
               "mass_scaling_step_s");
  expect_error("deformable: {model: fem, mass_scaling_max_fraction: 0.6}",
               "deformable.mass_scaling_max_fraction");
  expect_error("deformable: {model: fem, mesh_file: a.obj, tet_mesh_file: b.msh}", "tet_mesh_file");
  expect_error("deformable: {radus_m: 1}", "radus_m");
  expect_error("deformable: {mass_kg: 1, density_kg_per_m3: 10}", "density_kg_per_m3");
  expect_error("deformable: {centre_m: [1, 2]}", "centre_m");
}

TEST(Model, MassesAndTablesOfThePaperSphere) {
  DeformableParams p;  // defaults: the paper's sphere, level 4, mass-spring
  const DeformableModel m = build(p);
  EXPECT_EQ(m.node_count, 2562);
  EXPECT_EQ(m.edges.cols(), 7680);
  EXPECT_TRUE(m.has_centre);
  EXPECT_NEAR(m.mass_kg.sum() + m.centre_mass_kg, p.mass_kg, 1e-12);
  EXPECT_NEAR(m.area_m2.sum(), 4 * M_PI * 0.25 * 0.25, 0.01);
  EXPECT_NEAR((m.rest_centre_m - p.centre_m).norm(), 0.0, 1e-9);
  EXPECT_TRUE((m.radial_k.array() > 0).all());
}

// ---------------------------------------------------------------------------------------------
// dynamics

class EveryModel : public ::testing::TestWithParam<std::tuple<ModelKind, IntegratorKind>> {};

// A vertex pushed 5 mm out returns; the whole shape comes back to rest when damped.
TEST_P(EveryModel, ReturnsToRestShapeWhenDamped) {
  const auto [model, integ] = GetParam();
  DeformableParams p = small_params(model, integ, 2);
  p.stiffness_damping_s = 2e-3;
  p.mass_damping_per_s = 2.0;
  const double dt = integ == IntegratorKind::kExplicitEuler ? 1e-4 : 5e-4;
  const DeformableModel m = build(p);
  DeformableState s = make_state(m);
  displace_radially(m, s, 0, 0.005);
  const double e0 = shape_error(m, s);
  EXPECT_NEAR(e0, 0.005, 1e-3);
  for (int k = 0; k < static_cast<int>(3.0 / dt); ++k) {
    ASSERT_EQ(step(m, s, dt, nullptr), StepStatus::kOk) << "step " << k;
  }
  EXPECT_LT(shape_error(m, s), 0.01 * e0) << to_string(model) << " " << to_string(integ);
  EXPECT_LT(kinetic_energy(m, s), 1e-9);
  EXPECT_EQ(s.fault_count, 0u);
}

// A step allocates nothing, for every model and integrator, with contact and a held node.
TEST_P(EveryModel, StepAllocatesNothing) {
  const auto [model, integ] = GetParam();
  DeformableParams p = small_params(model, integ, 2);
  p.gravity_mps2 = Eigen::Vector3d(0, 0, -9.81);
  teleop::sim::Plane floor;
  floor.offset_m = -0.25 + 0.01;  // the sphere starts 1 cm into the floor
  const DeformableModel m = build(p, {floor});
  DeformableState s = make_state(m);
  teleop::sim::EventQueue events;
  s.pinned[5] = 1;
  s.pin_target.col(5) = s.x.col(5) + Eigen::Vector3d(0, 0, 0.002);
  s.f_ext.col(7) << 0.1, 0, 0;
  step(m, s, 1e-4, &events);  // warm up (nothing lazily sized may remain)
  {
    teleop::test::NoAllocScope scope;
    for (int k = 0; k < 20; ++k) step(m, s, 1e-4, &events);
    EXPECT_EQ(scope.allocations(), 0u) << to_string(model) << " " << to_string(integ);
  }
  EXPECT_GT(s.contact_count, 0);
  EXPECT_EQ(s.fault_count, 0u);
}

INSTANTIATE_TEST_SUITE_P(All, EveryModel,
                         ::testing::Combine(::testing::ValuesIn(kModels),
                                            ::testing::ValuesIn(kIntegrators)),
                         [](const auto& param_info) {
                           return std::string(to_string(std::get<0>(param_info.param))) + "_" +
                                  to_string(std::get<1>(param_info.param));
                         });

class UndampedModel : public ::testing::TestWithParam<ModelKind> {};

// Undamped symplectic Euler: energy stays bounded over 1e5 steps (no drift, no growth).
TEST_P(UndampedModel, SymplecticEulerKeepsEnergyBounded) {
  DeformableParams p = small_params(GetParam(), IntegratorKind::kSymplecticEuler, 1);
  make_undamped(p);
  const DeformableModel m = build(p);
  DeformableState s = make_state(m);
  const double h = 1.0 / omega_max(m, s);  // h w_max = 1: half the stability limit
  displace_radially(m, s, 0, 0.005);
  perturb(s, 1e-4, 3);
  // symplectic Euler conserves a nearby "shadow" energy: the true energy oscillates around it
  // (by tens of percent at h w = 1) but neither drifts nor grows
  const double e0 = kinetic_energy(m, s) + elastic_energy(m, s);
  const int steps = 100000;
  double first_hi = 0.0, last_hi = 0.0, lo = e0, hi = e0;
  for (int k = 0; k < steps; ++k) {
    step(m, s, h, nullptr);
    const double e = kinetic_energy(m, s) + elastic_energy(m, s);
    lo = std::min(lo, e);
    hi = std::max(hi, e);
    if (k < steps / 10) first_hi = std::max(first_hi, e);
    if (k >= steps - steps / 10) last_hi = std::max(last_hi, e);
  }
  EXPECT_EQ(s.fault_count, 0u);
  EXPECT_LT(hi, 2.0 * e0) << to_string(GetParam());
  EXPECT_GT(lo, 0.3 * e0) << to_string(GetParam());
  EXPECT_LT(last_hi, 1.1 * first_hi) << to_string(GetParam()) << ": energy grows";
}

INSTANTIATE_TEST_SUITE_P(All, UndampedModel, ::testing::ValuesIn(kModels),
                         [](const auto& param_info) {
                           return std::string(to_string(param_info.param));
                         });

// Runs an undamped body from a tiny random perturbation; true if it neither blew up nor grew.
bool stays_bounded(const DeformableModel& m, double h, int steps) {
  DeformableState s = make_state(m);
  perturb(s, 1e-6, 11);
  const double e0 = kinetic_energy(m, s) + elastic_energy(m, s);
  for (int k = 0; k < steps; ++k) {
    if (step(m, s, h, nullptr) == StepStatus::kFaultReset) return false;
  }
  const double e = kinetic_energy(m, s) + elastic_energy(m, s);
  return s.fault_count == 0 && e < 1e4 * e0;
}

// The largest stable step of symplectic Euler, found by bisection, is 2 / w_max (within 10%),
// with w_max from the eigenvalues of the mass-normalised stiffness. Explicit Euler diverges at
// that step; implicit Euler stays bounded at ten times it.
TEST_P(UndampedModel, StabilityLimitMatchesLargestEigenvalue) {
  DeformableParams p = small_params(GetParam(), IntegratorKind::kSymplecticEuler, 1);
  make_undamped(p);
  p.max_substeps = 1;  // the integrator's own limit: no automatic sub-steps
  const DeformableModel m = build(p);
  const DeformableState s0 = make_state(m);
  const double w = omega_max(m, s0);
  const double h_theory = 2.0 / w;
  double lo = 0.5 * h_theory, hi = 1.5 * h_theory;
  ASSERT_TRUE(stays_bounded(m, lo, 4000));
  ASSERT_FALSE(stays_bounded(m, hi, 4000));
  for (int it = 0; it < 14; ++it) {
    const double mid = 0.5 * (lo + hi);
    (stays_bounded(m, mid, 4000) ? lo : hi) = mid;
  }
  const double h_found = 0.5 * (lo + hi);
  EXPECT_NEAR(h_found * w, 2.0, 0.2) << to_string(GetParam()) << " w_max " << w << " rad/s";
  // explicit Euler diverges at the symplectic limit (at 0.9 of it, too)
  DeformableParams pe = p;
  pe.integrator = IntegratorKind::kExplicitEuler;
  const DeformableModel me = build(pe);
  EXPECT_FALSE(stays_bounded(me, 0.9 * h_found, 4000));
  // implicit Euler is bounded (and dissipates) at ten times the limit
  DeformableParams pi = p;
  pi.integrator = IntegratorKind::kImplicitEuler;
  const DeformableModel mi = build(pi);
  DeformableState si = make_state(mi);
  perturb(si, 1e-4, 5);
  const double e0 = kinetic_energy(mi, si) + elastic_energy(mi, si);
  for (int k = 0; k < 2000; ++k) step(mi, si, 10 * h_found, nullptr);
  EXPECT_EQ(si.fault_count, 0u);
  EXPECT_LT(kinetic_energy(mi, si) + elastic_energy(mi, si), e0);
}

class OrderTest : public ::testing::TestWithParam<IntegratorKind> {};

// Halving dt halves the error: all three schemes are first order.
TEST_P(OrderTest, HalvingStepHalvesError) {
  DeformableParams p = small_params(ModelKind::kMassSpring, GetParam(), 1);
  p.cg_tolerance = 1e-13;
  p.cg_max_iterations = 1000;
  const DeformableModel m = build(p);
  const double t_end = 0.02;
  auto run = [&](double h) {
    DeformableState s = make_state(m);
    displace_radially(m, s, 0, 0.005);
    const int steps = static_cast<int>(std::lround(t_end / h));
    for (int k = 0; k < steps; ++k) step(m, s, h, nullptr);
    return Eigen::Matrix3Xd(s.x);
  };
  const Eigen::Matrix3Xd ref = run(t_end / 20480);
  double err[3];
  for (int k = 0; k < 3; ++k) err[k] = (run(t_end / (200 << k)) - ref).norm();
  const double r1 = err[0] / err[1], r2 = err[1] / err[2];
  EXPECT_NEAR(r1, 2.0, 0.4) << to_string(GetParam()) << " errors " << err[0] << " " << err[1];
  EXPECT_NEAR(r2, 2.0, 0.4) << to_string(GetParam()) << " errors " << err[1] << " " << err[2];
}

INSTANTIATE_TEST_SUITE_P(All, OrderTest, ::testing::ValuesIn(kIntegrators),
                         [](const auto& param_info) {
                           return std::string(to_string(param_info.param));
                         });

// ---------------------------------------------------------------------------------------------
// rotation: the linear strain of the paper is not invariant, the co-rotational variant is

TEST(Rotation, LinearStrainResistsRigidRotationCorotationalDoesNot) {
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.5, Eigen::Vector3d(1, 2, 3).normalized()).matrix();
  double force[2];
  int idx = 0;
  for (ModelKind k : {ModelKind::kNavierLinear, ModelKind::kNavierCorotational}) {
    DeformableParams p = small_params(k, IntegratorKind::kSymplecticEuler, 2);
    const DeformableModel m = build(p);
    DeformableState s = make_state(m);
    s.x = r * m.mesh.vertices;
    Eigen::Matrix3Xd f;
    internal_forces(m, s, f);
    force[idx++] = f.colwise().norm().maxCoeff();
  }
  EXPECT_GT(force[0], 1e-3);  // linear strain: spurious restoring forces
  EXPECT_LT(force[1], 1e-6);  // co-rotational: none
}

TEST(Rotation, CorotationalForcesAreTheTextbookFormulaOnPolarFrames) {
  // a deformed, rotated, moving level-3 body: every node's frame is the polar factor of its ring
  // matrix (from an SVD here), and every node's force is the sum over its edges of
  // R (a g + b (g . u0) u0), g = R^T ((x_j - x_i) + beta (v_j - v_i)) - (X_j - X_i),
  // R = (R_i + R_j) / 2, written out with Eigen
  DeformableParams p =
      small_params(ModelKind::kNavierCorotational, IntegratorKind::kSymplecticEuler, 3);
  p.stiffness_damping_s = 2e-3;
  const DeformableModel m = build(p);
  DeformableState s = make_state(m);
  const Eigen::Matrix3d rot =
      Eigen::AngleAxisd(0.4, Eigen::Vector3d(1, -2, 1).normalized()).matrix();
  const Eigen::Matrix3Xd X = m.mesh.vertices;
  s.x = rot * X;
  for (int i = 0; i < m.node_count; ++i) {
    const double phase = 0.37 * i;
    s.x.col(i) +=
        0.004 * Eigen::Vector3d(std::sin(phase), std::cos(1.3 * phase), std::sin(2.1 * phase));
    s.v.col(i) = 0.05 * Eigen::Vector3d(std::cos(phase), std::sin(0.7 * phase), 0.3);
  }
  Eigen::Matrix3Xd f;
  internal_forces(m, s, f);
  const int n = m.node_count;
  Eigen::Vector3d c = Eigen::Vector3d::Zero(), c0 = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    c += m.mass_kg(i) * s.x.col(i);
    c0 += m.mass_kg(i) * X.col(i);
  }
  c /= m.mass_kg.sum();
  c0 /= m.mass_kg.sum();
  double frame_err = 0.0;
  for (int i = 0; i < n; ++i) {
    Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
    double len2 = 0.0;
    const auto& off = m.mesh.vertex_neighbour_offsets;
    for (int k = off[static_cast<std::size_t>(i)]; k < off[static_cast<std::size_t>(i) + 1]; ++k) {
      const int j = m.mesh.vertex_neighbours[static_cast<std::size_t>(k)];
      a += (s.x.col(j) - s.x.col(i)) * (X.col(j) - X.col(i)).transpose();
      len2 += (X.col(j) - X.col(i)).squaredNorm();
    }
    const Eigen::Vector3d rx = X.col(i) - c0;
    a += (len2 / rx.squaredNorm()) * (s.x.col(i) - c) * rx.transpose();
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(a, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Matrix3d polar = svd.matrixU() * svd.matrixV().transpose();
    frame_err = std::max(frame_err, (polar - s.rotation[static_cast<std::size_t>(i)]).norm());
  }
  EXPECT_LT(frame_err, 1e-9);
  Eigen::Matrix3Xd expect = Eigen::Matrix3Xd::Zero(3, n);
  for (int e = 0; e < m.edges.cols(); ++e) {
    const int i = m.edges(0, e), j = m.edges(1, e);
    const Eigen::Matrix3d r =
        0.5 * (s.rotation[static_cast<std::size_t>(i)] + s.rotation[static_cast<std::size_t>(j)]);
    const Eigen::Vector3d q =
        (s.x.col(j) - s.x.col(i)) + p.stiffness_damping_s * (s.v.col(j) - s.v.col(i));
    const Eigen::Vector3d g = r.transpose() * q - (X.col(j) - X.col(i));
    const Eigen::Vector3d u0 = m.rest_dir.col(e);
    const Eigen::Vector3d fe = r * (m.edge_k_iso(e) * g + m.edge_k_dir(e) * g.dot(u0) * u0);
    expect.col(i) += fe;
    expect.col(j) -= fe;
  }
  const double scale = expect.colwise().norm().maxCoeff();
  ASSERT_GT(scale, 1e-3);
  EXPECT_LT((f - expect).colwise().norm().maxCoeff(), 1e-9 * scale);
}

// ---------------------------------------------------------------------------------------------
// loads and constraints

TEST(Loads, PinnedNodeFollowsTargetAndNeighboursFollow) {
  DeformableParams p = small_params(ModelKind::kNavierLinear, IntegratorKind::kSymplecticEuler, 2);
  p.stiffness_damping_s = 5e-3;
  p.mass_damping_per_s = 5.0;
  const DeformableModel m = build(p);
  DeformableState s = make_state(m);
  const Eigen::Vector3d target = 0.99 * s.x.col(0);  // 2.5 mm inward, held
  s.pinned[0] = 1;
  s.pin_target.col(0) = target;
  for (int k = 0; k < 4000; ++k) step(m, s, 5e-4, nullptr);
  EXPECT_EQ((s.x.col(0) - target).norm(), 0.0);
  const int nb = m.mesh.vertex_neighbours[0];
  EXPECT_LT(s.x.col(nb).norm(), m.mesh.vertices.col(nb).norm() - 1e-5);  // dragged inward
  // the body swings slowly about the held node (as in the paper's Fig. 7); bounded, small
  EXPECT_LT(kinetic_energy(m, s), 1e-3);
}

TEST(Loads, PointForceDeformsAndReleases) {
  DeformableParams p = small_params(ModelKind::kMassSpring, IntegratorKind::kImplicitEuler, 2);
  p.mass_damping_per_s = 5.0;
  const DeformableModel m = build(p);
  DeformableState s = make_state(m);
  s.f_ext.col(0) = -0.5 * m.mesh.vertices.col(0).normalized();  // 0.5 N inward
  for (int k = 0; k < 2000; ++k) step(m, s, 1e-3, nullptr);
  const double dented = m.mesh.vertices.col(0).norm() - (s.x.col(0) - s.centre_x).norm();
  EXPECT_GT(dented, 1e-4);
  s.f_ext.setZero();
  for (int k = 0; k < 3000; ++k) step(m, s, 1e-3, nullptr);
  EXPECT_LT(shape_error(m, s), 1e-5);
}

TEST(Loads, DroppedSphereSettlesOnTheFloorAndSleeps) {
  DeformableParams p = small_params(ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler, 2);
  p.gravity_mps2 = Eigen::Vector3d(0, 0, -9.81);
  p.centre_m = Eigen::Vector3d(0, 0, 0.4);  // 15 cm above the floor
  p.sleep_time_s = 0.2;
  teleop::sim::Plane floor;
  floor.name = "floor";
  teleop::sim::Plane wall;
  wall.normal = Eigen::Vector3d(-1, 0, 0);
  wall.offset_m = -0.3;  // x <= 0.3
  const DeformableModel m = build(p, {floor, wall});
  DeformableState s = make_state(m);
  double min_z = 1.0;
  int sleeping = 0;
  for (int k = 0; k < 6000; ++k) {
    if (step(m, s, 1e-3, nullptr) == StepStatus::kSleeping) ++sleeping;
    min_z = std::min(min_z, s.x.row(2).minCoeff());
  }
  const Eigen::Vector3d c = centroid(m, s);
  EXPECT_GT(c.z(), 0.20);  // resting: squashed a little, not fallen through
  EXPECT_LT(c.z(), 0.25);
  EXPECT_GT(min_z, -0.01);  // penetration of the floor stays small
  EXPECT_GT(s.x.row(2).minCoeff(), -0.005);
  EXPECT_TRUE(s.sleeping);
  EXPECT_GT(sleeping, 100);
  EXPECT_EQ(s.fault_count, 0u);
  // a load wakes it
  s.f_ext.col(0) << 1.0, 0, 0;
  EXPECT_EQ(step(m, s, 1e-3, nullptr), StepStatus::kOk);
  EXPECT_FALSE(s.sleeping);
}

TEST(Sleep, UntouchedBodyAtRestSleepsAndSkipsWork) {
  DeformableParams p = small_params(ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler, 2);
  p.sleep_time_s = 0.05;
  const DeformableModel m = build(p);
  DeformableState s = make_state(m);
  int k = 0;
  while (!s.sleeping && k < 1000) {
    step(m, s, 1e-3, nullptr);
    ++k;
  }
  EXPECT_TRUE(s.sleeping);
  EXPECT_LE(k, 60);
  const Eigen::Matrix3Xd before = s.x;
  EXPECT_EQ(step(m, s, 1e-3, nullptr), StepStatus::kSleeping);
  EXPECT_EQ(s.x, before);
  // a held node away from its target wakes it
  s.pinned[3] = 1;
  s.pin_target.col(3) = s.x.col(3) * 1.01;
  EXPECT_EQ(step(m, s, 1e-3, nullptr), StepStatus::kOk);
  EXPECT_FALSE(s.sleeping);
}

// ---------------------------------------------------------------------------------------------
// faults

TEST(Faults, BlowUpIsDetectedReportedAndReset) {
  DeformableParams p = small_params(ModelKind::kMassSpring, IntegratorKind::kExplicitEuler, 1);
  make_undamped(p);
  const DeformableModel m = build(p);
  DeformableState s = make_state(m);
  s.x += Eigen::Matrix3Xd::Constant(3, m.node_count, 0.3);  // move it: reset keeps the place
  s.last_good_centroid = centroid(m, s);
  displace_radially(m, s, 0, 0.01);
  teleop::sim::EventQueue events;
  StepStatus st = StepStatus::kOk;
  int k = 0;
  for (; k < 10000 && st != StepStatus::kFaultReset; ++k) st = step(m, s, 0.05, &events);
  ASSERT_EQ(st, StepStatus::kFaultReset) << "explicit Euler at a huge step must blow up";
  EXPECT_EQ(s.fault_count, 1u);
  teleop::sim::SimEvent ev;
  ASSERT_TRUE(events.pop(ev));
  // first the warning that explicit Euler without damping is unstable at any step
  EXPECT_EQ(ev.kind, teleop::sim::EventKind::kInfo);
  EXPECT_NE(std::string(ev.message).find("unstable at any step"), std::string::npos);
  ASSERT_TRUE(events.pop(ev));
  EXPECT_EQ(ev.kind, teleop::sim::EventKind::kFault);
  EXPECT_NE(std::string(ev.message).find("blow-up"), std::string::npos);
  EXPECT_TRUE(s.x.allFinite());
  EXPECT_LT(shape_error(m, s), 1e-12);  // rest shape
  EXPECT_EQ(s.v.norm(), 0.0);
  EXPECT_LT((centroid(m, s) - Eigen::Vector3d::Constant(0.3)).norm(), 0.5);
}

TEST(Faults, NanIsDetectedAndBadInputRefused) {
  DeformableParams p =
      small_params(ModelKind::kNavierCorotational, IntegratorKind::kImplicitEuler, 1);
  const DeformableModel m = build(p);
  DeformableState s = make_state(m);
  teleop::sim::EventQueue events;
  s.x(0, 4) = std::nan("");
  EXPECT_EQ(step(m, s, 1e-3, &events), StepStatus::kFaultReset);
  EXPECT_TRUE(s.x.allFinite());
  EXPECT_EQ(step(m, s, 1e-3, &events), StepStatus::kOk);
  s.f_ext(1, 2) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(step(m, s, 1e-3, &events), StepStatus::kBadInput);
  s.f_ext.setZero();
  EXPECT_EQ(step(m, s, -1.0, &events), StepStatus::kBadInput);
  EXPECT_EQ(step(m, s, std::nan(""), &events), StepStatus::kBadInput);
  EXPECT_EQ(events.size(), 4u);
  EXPECT_TRUE(s.x.allFinite());
}

}  // namespace

namespace {

// The scene files in deploy/scenes/ hold valid `deformable:` mappings that build a model.
TEST(Scenes, SphereScenesLoad) {
  for (const char* name : {"sphere_zero_g.yaml", "sphere_gravity.yaml", "sphere_navier.yaml"}) {
    SCOPED_TRACE(name);
    const auto root =
        teleop::config::Node::load_file(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/" + name);
    auto p = teleop::sim::deformable::load_deformable_params(root.at("deformable"));
    p.level = 2;  // keep the test small
    const auto m =
        teleop::sim::deformable::make_model(teleop::sim::deformable::make_mesh_for(p), p);
    EXPECT_EQ(m.node_count, 162);
    EXPECT_GT(m.total_mass_kg, 1.0);
  }
}

}  // namespace

namespace {

using namespace teleop::sim::deformable;
using namespace teleop::sim::deformable::testing;

// Mean horizontal velocity of the body (nodes and centre node) [m/s].
double mean_vx(const DeformableModel& m, const DeformableState& s) {
  return (s.v.row(0).dot(m.mass_kg) + m.centre_mass_kg * s.centre_v.x()) / m.total_mass_kg;
}

// A sphere resting on the floor and set sliding: without friction nothing acts horizontally
// and it keeps its speed; with Coulomb friction the floor slows the sliding down.
TEST(Contact, FrictionSlowsASlidingSphere) {
  double final_vx[2];
  for (int with_friction = 0; with_friction < 2; ++with_friction) {
    DeformableParams p = small_params(ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler, 2);
    p.gravity_mps2 = Eigen::Vector3d(0, 0, -9.81);
    p.centre_m = Eigen::Vector3d(0, 0, 0.245);
    p.friction = with_friction == 1;
    teleop::sim::Plane floor;
    floor.friction = 0.5;
    const DeformableModel m = build(p, {floor});
    DeformableState s = make_state(m);
    for (int k = 0; k < 1000; ++k) step(m, s, 1e-3, nullptr);  // settle on the floor
    s.v.row(0).array() += 0.5;
    s.centre_v.x() += 0.5;
    for (int k = 0; k < 500; ++k) step(m, s, 1e-3, nullptr);
    final_vx[with_friction] = mean_vx(m, s);
    EXPECT_EQ(s.fault_count, 0u);
  }
  EXPECT_NEAR(final_vx[0], 0.5, 1e-6);  // frictionless: momentum kept
  EXPECT_LT(final_vx[1], 0.45);         // friction: slowed (towards rolling)
  EXPECT_GT(final_vx[1], 0.0);
}

// Thrown at a wall, the sphere is stopped and pushed back; no node ends beyond the wall.
TEST(Contact, WallStopsAndReturnsTheSphere) {
  DeformableParams p = small_params(ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler, 2);
  teleop::sim::Plane wall;
  wall.normal = Eigen::Vector3d(-1, 0, 0);
  wall.offset_m = -0.3;  // free space: x <= 0.3
  const DeformableModel m = build(p, {wall});
  DeformableState s = make_state(m);
  s.v.row(0).setConstant(1.0);
  s.centre_v.x() = 1.0;
  double max_x = 0.0;
  for (int k = 0; k < 600; ++k) {
    step(m, s, 1e-3, nullptr);
    max_x = std::max(max_x, s.x.row(0).maxCoeff());
  }
  EXPECT_LT(mean_vx(m, s), 0.0);  // bounced back
  EXPECT_LT(max_x, 0.3 + 0.02);   // penetration of the wall stays below 2 cm
  EXPECT_EQ(s.fault_count, 0u);
}

// The fused kernel that mass-spring bodies with symplectic Euler take must do what the general
// force and integration passes do: same positions, velocities, forces, contacts and plane force,
// up to rounding (the edge forces are summed in another order), through gravity, drag, a point
// load, a held node, the floor and a wall with friction. Measured: 3e-16 m, 7e-14 m/s, 8e-14 N.
TEST(FusedStep, MatchesTheGeneralPasses) {
  DeformableParams p = small_params(ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler, 3);
  const DeformableModel m = build_on_floor_by_wall(p);
  DeformableState fused = make_state(m);
  fused.v.row(0).setConstant(0.3);  // thrown at the wall
  fused.centre_v.x() = 0.3;
  DeformableState general = fused;
  double worst_x = 0.0, worst_v = 0.0, worst_f = 0.0, worst_plane = 0.0;
  int contact_steps = 0;
  for (int k = 0; k < 4000; ++k) {
    for (DeformableState* s : {&fused, &general}) {
      s->f_ext.setZero();
      if (k >= 200 && k < 700) s->f_ext.col(5) = Eigen::Vector3d(0.0, 2.0, -1.0);  // a push
      if (k == 800) {
        s->pinned[17] = 1;
        s->pin_target.col(17) = s->x.col(17) + Eigen::Vector3d(0.0, 0.0, 0.01);
      }
      if (k == 1200) s->pinned[17] = 0;
    }
    const StepStatus a = step(m, fused, 1e-3, nullptr);
    const StepStatus b = detail::step_general(m, general, 1e-3, nullptr);
    ASSERT_EQ(a, b) << "step " << k;
    ASSERT_EQ(fused.contact_count, general.contact_count) << "step " << k;
    worst_x = std::max(worst_x, (fused.x - general.x).cwiseAbs().maxCoeff());
    worst_v = std::max(worst_v, (fused.v - general.v).cwiseAbs().maxCoeff());
    worst_x = std::max(worst_x, (fused.centre_x - general.centre_x).cwiseAbs().maxCoeff());
    if (a == StepStatus::kOk) {
      worst_f = std::max(worst_f, (fused.force - general.force).cwiseAbs().maxCoeff());
    }
    worst_plane = std::max(worst_plane, (fused.plane_force_n - general.plane_force_n).norm());
    contact_steps += fused.contact_count > 0 ? 1 : 0;
  }
  EXPECT_GT(contact_steps, 3000);  // the floor and the wall were exercised
  EXPECT_EQ(fused.fault_count, 0u);
  EXPECT_LT(worst_x, 1e-12);  // [m]
  EXPECT_LT(worst_v, 1e-10);  // [m/s]
  EXPECT_LT(worst_f, 1e-10);  // [N]
  EXPECT_LT(worst_plane, 1e-10);
}

}  // namespace
