// The automatic step and the simd kernel: the highest natural
// frequency against dense eigenvalues, power iteration and the Gershgorin bound; sub-stepping of
// stiff bodies under a point load, a held node and a tip press with no fault; the paper
// scene's path untouched; the simd kernel against the general passes.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

#include "server/deformable/deformable.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/unit/server/deformable/test_helpers.hpp"

namespace {

using namespace teleop::sim::deformable;
using namespace teleop::sim::deformable::testing;
using teleop::config::ConfigError;
using teleop::config::Node;

// ---------------------------------------------------------------------------------------------
// the estimate of w_max

class EveryModelKind : public ::testing::TestWithParam<ModelKind> {};

// Lanczos (the model's estimate) against Eigen's dense eigenvalues of the finite-difference
// stiffness, levels 1 and 2: equal to 1e-6 (co-rotational: at most 1 % above); below the block
// Gershgorin bound.
TEST_P(EveryModelKind, OmegaMaxMatchesDenseEigenvaluesAndGershgorinBoundsIt) {
  for (int level : {1, 2}) {
    const DeformableParams p = small_params(GetParam(), IntegratorKind::kSymplecticEuler, level);
    const DeformableModel m = build(p);
    const double dense = omega_max(m, make_state(m));
    if (GetParam() == ModelKind::kNavierCorotational) {
      // the estimate uses the linear-strain stiffness; co-rotation removes the stiffness of
      // rotation-like motions, so the true value is slightly lower: conservative, within 1 %
      EXPECT_GE(m.omega_max_rad_per_s, dense * (1.0 - 1e-9)) << level;
      EXPECT_LT(m.omega_max_rad_per_s, 1.01 * dense) << level;
    } else {
      EXPECT_NEAR(m.omega_max_rad_per_s / dense, 1.0, 1e-6)
          << to_string(GetParam()) << " " << level;
    }
    EXPECT_LE(m.omega_max_rad_per_s, m.omega_bound_rad_per_s);
    EXPECT_DOUBLE_EQ(m.omega_bound_rad_per_s, gershgorin_omega_bound(m));
  }
}

INSTANTIATE_TEST_SUITE_P(All, EveryModelKind,
                         ::testing::Values(ModelKind::kMassSpring, ModelKind::kNavierLinear,
                                           ModelKind::kNavierCorotational),
                         [](const auto& param_info) {
                           return std::string(to_string(param_info.param));
                         });

// Plain power iteration on M^-1 K of the paper's sphere (level 4, default parameters), K applied
// by central differences of internal_forces (independent of the model's own estimate):
// power iteration <= Lanczos (both approach w_max from below; Lanczos faster) <= Gershgorin.
TEST(OmegaMax, PowerIterationAgreesWithTheEstimateOnThePaperSphere) {
  DeformableParams p;
  p.gravity_mps2.setZero();
  const DeformableModel m = build(p);
  DeformableState s = make_state(m);
  const int n = m.node_count;
  const int dofs = 3 * n + 3;
  Eigen::VectorXd mass(dofs);
  for (int i = 0; i < n; ++i) mass.segment<3>(3 * i).setConstant(m.mass_kg(i));
  mass.tail<3>().setConstant(m.centre_mass_kg);
  const Eigen::Matrix3Xd x0 = s.x;
  const Eigen::Vector3d c0 = s.centre_x;
  Eigen::Matrix3Xd f;
  auto forces_at = [&](const Eigen::VectorXd& dx, Eigen::VectorXd& out) {
    for (int i = 0; i < n; ++i) s.x.col(i) = x0.col(i) + dx.segment<3>(3 * i);
    s.centre_x = c0 + dx.tail<3>();
    internal_forces(m, s, f);
    out.resize(dofs);
    for (int i = 0; i < n; ++i) out.segment<3>(3 * i) = f.col(i);
    out.tail<3>() = s.work_f.col(n);
  };
  auto apply_k = [&](const Eigen::VectorXd& q, Eigen::VectorXd& out) {
    const double eps = 1e-6 / q.cwiseAbs().maxCoeff();
    Eigen::VectorXd fp, fm;
    forces_at(eps * q, fp);
    forces_at(-eps * q, fm);
    out = -(fp - fm) / (2.0 * eps);
  };
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::VectorXd q(dofs), kq;
  for (int k = 0; k < dofs; ++k) q(k) = u(rng);
  double lambda = 0.0;
  for (int it = 0; it < 3000; ++it) {
    q /= std::sqrt(q.dot(mass.cwiseProduct(q)));
    apply_k(q, kq);
    lambda = q.dot(kq);  // Rayleigh quotient q^T K q / q^T M q (q is M-normalised)
    q = kq.cwiseQuotient(mass);
  }
  const double w_power = std::sqrt(lambda);
  RecordProperty("w_power", std::to_string(w_power));
  RecordProperty("w_lanczos", std::to_string(m.omega_max_rad_per_s));
  RecordProperty("w_gershgorin", std::to_string(m.omega_bound_rad_per_s));
  std::printf(
      "w_max level 4: power iteration (3000) %.2f, Lanczos (%d) %.2f, Gershgorin %.2f "
      "rad/s; top-mode zeta %.3f, stable step %.4f ms\n",
      w_power, kStabilityLanczosIterations, m.omega_max_rad_per_s, m.omega_bound_rad_per_s,
      m.damping_ratio_top, m.stable_step_s * 1e3);
  EXPECT_LE(w_power, m.omega_max_rad_per_s * (1.0 + 1e-6));
  EXPECT_GT(w_power, 0.97 * m.omega_max_rad_per_s);
  EXPECT_LT(m.omega_max_rad_per_s, m.omega_bound_rad_per_s);
  EXPECT_NEAR(m.omega_max_rad_per_s, 1329.0, 5.0);  // docs/deformable.md
}

// The stable step of each integrator: symplectic Euler h = s * 2 (sqrt(1 + z^2) - z) / w;
// implicit Euler never sub-steps; substeps_for is ceil(dt / h), capped by max_substeps.
TEST(AutoStep, StableStepFormulaAndSubstepCount) {
  DeformableParams p = small_params(ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler, 2);
  const DeformableModel m = build(p);
  const double w = m.omega_max_rad_per_s, z = m.damping_ratio_top;
  EXPECT_GT(z, 0.0);
  EXPECT_NEAR(m.stable_step_s, kStableStepSafety * 2.0 * (std::sqrt(1 + z * z) - z) / w, 1e-15);
  EXPECT_EQ(m.substeps_for(0.5 * m.stable_step_s), 1);
  EXPECT_EQ(m.substeps_for(m.stable_step_s), 1);
  EXPECT_EQ(m.substeps_for(2.5 * m.stable_step_s), 3);
  EXPECT_EQ(m.substeps_for(1e3 * m.stable_step_s), p.max_substeps);
  EXPECT_EQ(m.substeps_needed(1e3 * m.stable_step_s), 1000);
  DeformableParams undamped = p;
  make_undamped(undamped);
  const DeformableModel mu = build(undamped);
  EXPECT_EQ(mu.damping_ratio_top, 0.0);
  EXPECT_NEAR(mu.stable_step_s * mu.omega_max_rad_per_s, kStableStepSafety * 2.0, 1e-12);
  DeformableParams pi = p;
  pi.integrator = IntegratorKind::kImplicitEuler;
  const DeformableModel mi = build(pi);
  EXPECT_TRUE(std::isinf(mi.stable_step_s));
  EXPECT_EQ(mi.substeps_for(1.0), 1);
  // stiffer: w grows as sqrt(k), the step shrinks
  DeformableParams stiff = p;
  stiff.edge_stiffness_n_per_m *= 4.0;
  stiff.radial_stiffness_n_per_m3 *= 4.0;
  const DeformableModel ms = build(stiff);
  EXPECT_NEAR(ms.omega_max_rad_per_s / w, 2.0, 1e-6);
  EXPECT_LT(ms.stable_step_s, m.stable_step_s);
  // update_stable_step after changing stiffness in place gives what make_model gives
  DeformableModel changed = m;
  changed.edge_k_iso *= 4.0;
  changed.radial_k *= 4.0;
  update_stable_step(changed);
  EXPECT_NEAR(changed.omega_max_rad_per_s, ms.omega_max_rad_per_s, 1e-9 * w);
}

// The undamped stability limit found by bisection (as in deformable_test) sits above the stable
// step the model computes, and within 1 / safety of it.
TEST(AutoStep, StableStepIsBelowTheMeasuredLimit) {
  DeformableParams p = small_params(ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler, 2);
  p.sleep_time_s = 1e9;
  p.max_substeps = 1;  // measure single steps
  for (int damped = 0; damped < 2; ++damped) {
    DeformableParams q = p;
    if (damped == 0) make_undamped(q);
    const DeformableModel m = build(q);
    auto bounded = [&](double h) {
      DeformableState s = make_state(m);
      perturb(s, 1e-6, 11);
      for (int k = 0; k < 4000; ++k) {
        if (detail::step_once(m, s, h, nullptr) == StepStatus::kFaultReset) return false;
      }
      return s.x.allFinite() && shape_error(m, s) < 1e-3;
    };
    double lo = 0.5 * m.stable_step_s, hi = 3.0 * m.stable_step_s;
    ASSERT_TRUE(bounded(lo));
    ASSERT_FALSE(bounded(hi));
    for (int it = 0; it < 12; ++it) {
      const double mid = 0.5 * (lo + hi);
      (bounded(mid) ? lo : hi) = mid;
    }
    const double ratio = lo / m.stable_step_s;  // measured limit / computed stable step
    std::printf("%s: measured limit %.4f ms, computed limit %.4f ms, stable step %.4f ms\n",
                damped ? "damped" : "undamped", lo * 1e3, m.stable_step_s / kStableStepSafety * 1e3,
                m.stable_step_s * 1e3);
    EXPECT_GE(ratio, 1.0) << (damped ? "damped" : "undamped");
    EXPECT_LT(ratio, 1.1 / kStableStepSafety) << (damped ? "damped" : "undamped");
  }
}

// ---------------------------------------------------------------------------------------------
// the paper's sphere with stiffness x3 and x10 under the probes of the other tests

enum class Probe { kPointLoad, kHeldNode, kTipPress };

const char* probe_name(Probe p) {
  switch (p) {
    case Probe::kPointLoad:
      return "point_load";
    case Probe::kHeldNode:
      return "held_node";
    case Probe::kTipPress:
      return "tip_press";
  }
  return "?";
}

// The paper scene's mass-spring sphere (level 4, on the floor at x = 0.6 beside the wall) with all
// its stiffnesses (edges, radial springs, Young's modulus) times `factor`.
DeformableParams paper_sphere(double factor) {
  const Node root =
      Node::load_file(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/paper_sphere.yaml");
  DeformableParams p = load_deformable_params(root.at("deformables").at(std::size_t{0}).at("body"));
  p.edge_stiffness_n_per_m *= factor;
  p.radial_stiffness_n_per_m3 *= factor;
  p.youngs_modulus_pa *= factor;
  return p;
}

std::vector<teleop::sim::Plane> paper_planes() {
  teleop::sim::Plane floor;
  floor.name = "floor";
  floor.friction = 0.5;
  teleop::sim::Plane wall;
  wall.name = "wall";
  wall.normal = Eigen::Vector3d(0, -1, 0);
  wall.offset_m = -0.6;
  wall.friction = 0.5;
  return {floor, wall};
}

struct ProbeRun {
  std::uint64_t faults = 0;
  int max_substeps = 0;
  int info_events = 0;
  double deepest_m = 0.0;  // how far the top node was pushed below its rest height
};

// 5000 steps of 1 ms: the probe acts from 0.5 s to 3 s, then the body is released.
ProbeRun run_probe(const DeformableModel& m, Probe probe, int steps = 5000) {
  DeformableState s = make_state(m);
  teleop::sim::EventQueue events;
  ProbeRun out;
  int top = 0;
  for (int i = 1; i < m.node_count; ++i) {
    if (m.mesh.vertices(2, i) > m.mesh.vertices(2, top)) top = i;
  }
  const Eigen::Vector3d top0 = m.mesh.vertices.col(top);
  const double dt = 1e-3;
  const double tip_r = 0.05, tip_k = 200.0;  // the paper scene's tip and node penalty
  for (int k = 0; k < steps; ++k) {
    const double t = k * dt;
    const bool active = t >= 0.5 && t < 3.0;
    const double ramp = active ? std::min(1.0, (t - 0.5) / 0.5) : 0.0;  // 0.5 s ramp in
    s.f_ext.setZero();
    switch (probe) {
      case Probe::kPointLoad:
        if (active) s.f_ext.col(top) = Eigen::Vector3d(0.0, 0.0, -2.0) * ramp;
        break;
      case Probe::kHeldNode:
        s.pinned[static_cast<std::size_t>(top)] = active ? 1 : 0;
        if (active) s.pin_target.col(top) = top0 + Eigen::Vector3d(0.0, 0.0, -0.03 * ramp);
        break;
      case Probe::kTipPress: {
        // a rigid tip sphere coming down onto the top, 3 cm deep, node penalty k (r - d) as the
        // world's tip contact does
        if (!active) break;
        const Eigen::Vector3d tip = top0 + Eigen::Vector3d(0.0, 0.0, tip_r - 0.03 * ramp);
        for (int i = 0; i < m.node_count; ++i) {
          const Eigen::Vector3d d = s.x.col(i) - tip;
          const double dist = d.norm();
          if (dist < tip_r && dist > 1e-9) s.f_ext.col(i) = tip_k * (tip_r - dist) * d / dist;
        }
        if (s.sleeping) wake(s);
        break;
      }
    }
    const StepStatus st = step(m, s, dt, &events);
    if (st == StepStatus::kFaultReset) ++out.faults;
    out.max_substeps = std::max(out.max_substeps, s.last_substeps);
    out.deepest_m = std::max(out.deepest_m, top0.z() - s.x(2, top));
  }
  teleop::sim::SimEvent ev;
  while (events.pop(ev)) {
    if (ev.kind == teleop::sim::EventKind::kInfo) ++out.info_events;
  }
  out.faults = s.fault_count;
  return out;
}

class StiffSphere : public ::testing::TestWithParam<std::tuple<double, Probe>> {};

// Stiffness x3 and x10 at dt = 1 ms: sub-stepped, no fault reset, one info event; the probe
// really deforms the body.
TEST_P(StiffSphere, RunsWithoutFaultResets) {
  const auto [factor, probe] = GetParam();
  const DeformableModel m = build(paper_sphere(factor), paper_planes());
  EXPECT_GT(m.substeps_for(1e-3), 1);
  const ProbeRun r = run_probe(m, probe);
  EXPECT_EQ(r.faults, 0u) << "x" << factor << " " << probe_name(probe);
  EXPECT_EQ(r.max_substeps, m.substeps_for(1e-3));
  EXPECT_EQ(r.info_events, 1);
  EXPECT_GT(r.deepest_m, 1e-3) << "the probe must dent the body";
  std::printf(
      "x%g %s: %d sub-steps of %.3f ms (w_max %.0f rad/s, zeta %.2f), faults %llu, "
      "top node down %.1f mm\n",
      factor, probe_name(probe), r.max_substeps, 1e3 * 1e-3 / r.max_substeps, m.omega_max_rad_per_s,
      m.damping_ratio_top, static_cast<unsigned long long>(r.faults), 1e3 * r.deepest_m);
}

INSTANTIATE_TEST_SUITE_P(All, StiffSphere,
                         ::testing::Combine(::testing::Values(3.0, 10.0),
                                            ::testing::Values(Probe::kPointLoad, Probe::kHeldNode,
                                                              Probe::kTipPress)),
                         [](const auto& param_info) {
                           return "x" +
                                  std::to_string(static_cast<int>(std::get<0>(param_info.param))) +
                                  "_" + probe_name(std::get<1>(param_info.param));
                         });

// The simd kernel sub-steps the same way: x10 under the tip press and the held node (the held
// node takes its per-node integration path), no fault.
TEST(StiffSphere, SimdKernelRunsWithoutFaultResets) {
  DeformableParams p = paper_sphere(10.0);
  p.kernel = KernelKind::kSimd;
  const DeformableModel m = build(p, paper_planes());
  for (Probe probe : {Probe::kTipPress, Probe::kHeldNode}) {
    const ProbeRun r = run_probe(m, probe);
    EXPECT_EQ(r.faults, 0u) << probe_name(probe);
    EXPECT_EQ(r.max_substeps, 6) << probe_name(probe);
    EXPECT_GT(r.deepest_m, 1e-3) << probe_name(probe);
  }
}

// Without the automatic step (max_substeps 1) the x3 sphere blows up at dt = 1 ms under the
// same probes: what the sub-steps prevent.
TEST(StiffSphereWithoutSubsteps, BlowsUp) {
  DeformableParams p = paper_sphere(3.0);
  p.max_substeps = 1;
  const DeformableModel m = build(p, paper_planes());
  EXPECT_EQ(m.substeps_for(1e-3), 1);
  EXPECT_GT(m.substeps_needed(1e-3), 1);
  for (Probe probe : {Probe::kPointLoad, Probe::kHeldNode, Probe::kTipPress}) {
    EXPECT_GT(run_probe(m, probe, 1000).faults, 0u) << probe_name(probe);
  }
}

// ---------------------------------------------------------------------------------------------
// the shipped scenes: no sub-step; the paper's sphere on the single-step code path

TEST(DefaultScene, DoesNotSubStepAtOneMillisecond) {
  for (const char* file : {"default.yaml", "paper_sphere.yaml", "sphere_gravity.yaml"}) {
    const Node root = Node::load_file(std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/" + file);
    const Node body = root.has("deformables") ? root.at("deformables").at(std::size_t{0}).at("body")
                                              : root.at("deformable");
    const DeformableParams p = load_deformable_params(body);
    const DeformableModel m = make_model(p, paper_planes());  // the mesh the model needs
    EXPECT_GT(m.stable_step_s, 1e-3) << file;
    EXPECT_EQ(m.substeps_for(1e-3), 1) << file;
  }
}

// step() of the paper's sphere at 1 ms is bit for bit detail::step_once (one step, no sub-step),
// through a drop onto the floor, a point load and a held node; no event is pushed.
TEST(PaperScene, StepIsBitIdenticalToTheSingleStep) {
  const DeformableModel m = build(paper_sphere(1.0), paper_planes());
  DeformableState a = make_state(m);
  for (int i = 0; i < m.node_count; ++i) a.x(2, i) += 0.02;  // dropped from 2 cm
  a.centre_x.z() += 0.02;
  DeformableState b = a;
  teleop::sim::EventQueue ev_a, ev_b;
  for (int k = 0; k < 1500; ++k) {
    for (DeformableState* s : {&a, &b}) {
      s->f_ext.setZero();
      if (k >= 300 && k < 600) s->f_ext.col(3) = Eigen::Vector3d(0.0, 0.5, -1.0);
      s->pinned[9] = k >= 700 && k < 1000 ? 1 : 0;
      if (k == 700) s->pin_target.col(9) = s->x.col(9) + Eigen::Vector3d(0.0, 0.0, -0.01);
    }
    ASSERT_EQ(step(m, a, 1e-3, &ev_a), detail::step_once(m, b, 1e-3, &ev_b)) << k;
    ASSERT_EQ(a.last_substeps, 1);
  }
  EXPECT_TRUE(a.x == b.x);
  EXPECT_TRUE(a.v == b.v);
  EXPECT_TRUE(a.centre_x == b.centre_x);
  EXPECT_TRUE(a.force == b.force);
  EXPECT_EQ(ev_a.size(), 0u);
  EXPECT_EQ(a.fault_count, 0u);
}

// ---------------------------------------------------------------------------------------------
// sub-stepping itself

// Sub-stepping allocates nothing, is deterministic, moves a held node to its target by the end
// of the step and leaves the caller's pin targets as they were.
TEST(AutoStep, SubStepsAllocateNothingAndAreDeterministic) {
  DeformableParams p = small_params(ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler, 2);
  p.gravity_mps2 = Eigen::Vector3d(0, 0, -9.81);
  p.edge_stiffness_n_per_m *= 10.0;
  p.radial_stiffness_n_per_m3 *= 10.0;
  teleop::sim::Plane floor;
  floor.offset_m = -0.25 + 0.005;
  const DeformableModel m = build(p, {floor});
  const double dt = 3.5 * m.stable_step_s;
  ASSERT_EQ(m.substeps_for(dt), 4);
  auto run = [&](DeformableState& s, teleop::sim::EventQueue& events, bool count) {
    s.pinned[5] = 1;
    const Eigen::Vector3d target = s.x.col(5) + Eigen::Vector3d(0.0, 0.0, 0.002);
    s.pin_target.col(5) = target;
    s.f_ext.col(7) << 0.1, 0, 0;
    step(m, s, dt, &events);  // warm up
    EXPECT_EQ(s.x.col(5), target);
    EXPECT_EQ(s.pin_target.col(5), target);
    teleop::test::NoAllocScope scope;
    for (int k = 0; k < 50; ++k) step(m, s, dt, &events);
    if (count) {
      EXPECT_EQ(scope.allocations(), 0u);
    }
  };
  DeformableState a = make_state(m), b = make_state(m);
  teleop::sim::EventQueue ea, eb;
  run(a, ea, true);
  run(b, eb, false);
  EXPECT_TRUE(a.x == b.x);
  EXPECT_TRUE(a.v == b.v);
  EXPECT_EQ(a.last_substeps, 4);
  EXPECT_EQ(a.fault_count, 0u);
  EXPECT_GT(a.contact_count, 0);
  ASSERT_EQ(ea.size(), 1u);  // announced once
  teleop::sim::SimEvent ev;
  ASSERT_TRUE(ea.pop(ev));
  EXPECT_EQ(ev.kind, teleop::sim::EventKind::kInfo);
  EXPECT_EQ(ev.value, 4.0);
  EXPECT_NE(std::string(ev.message).find("4 sub-steps"), std::string::npos) << ev.message;
  EXPECT_NEAR(a.sim_time_s, 51 * dt, 1e-12);
}

// The cap: more sub-steps needed than max_substeps gives a warning that says so.
TEST(AutoStep, CapIsAnnouncedAsAWarning) {
  DeformableParams p = small_params(ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler, 1);
  p.max_substeps = 2;
  const DeformableModel m = build(p);
  DeformableState s = make_state(m);
  teleop::sim::EventQueue events;
  step(m, s, 10.0 * m.stable_step_s, &events);
  EXPECT_EQ(s.last_substeps, 2);
  teleop::sim::SimEvent ev;
  ASSERT_TRUE(events.pop(ev));
  EXPECT_EQ(ev.severity, teleop::sim::Severity::kWarning);
  EXPECT_NE(std::string(ev.message).find("capped at 2"), std::string::npos) << ev.message;
}

TEST(AutoStep, ParamsAreValidated) {
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
  expect_error("deformable: {max_substeps: 0}", "deformable.max_substeps");
  expect_error("deformable: {kernel: gpu}", "deformable.kernel");
  expect_error("deformable: {kernel: simd, model: navier_linear}", "deformable.kernel");
  expect_error("deformable: {kernel: simd, integrator: implicit_euler}", "deformable.kernel");
  const Node ok = Node::parse("deformable: {kernel: simd, max_substeps: 8}", "ok.yaml");
  const DeformableParams p = load_deformable_params(ok.at("deformable"));
  EXPECT_EQ(p.kernel, KernelKind::kSimd);
  EXPECT_EQ(p.max_substeps, 8);
  DeformableParams navier = p;
  navier.model = ModelKind::kNavierLinear;
  EXPECT_THROW(build(navier), ConfigError);
  // no `kernel`: simd for mass_spring + symplectic_euler where the CPU runs its AVX2 path,
  // scalar for every other model and integrator; `kernel: scalar` is kept
  const auto kernel_of = [](const std::string& yaml) {
    const Node n = Node::parse(yaml, "k.yaml");
    return load_deformable_params(n.at("deformable")).kernel;
  };
  EXPECT_EQ(kernel_of("deformable: {level: 2}"),
            simd_kernel_vectorised() ? KernelKind::kSimd : KernelKind::kScalar);
  EXPECT_EQ(kernel_of("deformable: {level: 2, kernel: scalar}"), KernelKind::kScalar);
  EXPECT_EQ(kernel_of("deformable: {level: 2, model: navier_linear}"), KernelKind::kScalar);
  EXPECT_EQ(kernel_of("deformable: {level: 2, integrator: implicit_euler}"), KernelKind::kScalar);
#if defined(__x86_64__)
  EXPECT_EQ(simd_kernel_vectorised(),
            __builtin_cpu_supports("avx2") != 0 && __builtin_cpu_supports("fma") != 0);
#endif
}

// ---------------------------------------------------------------------------------------------
// kernel simd

// The loads of the kernels' obstacle course at step k: a point load on node 5 for steps
// 200-499, node 17 held 1 cm above where it is from step 600, released at step 800.
void course_loads(DeformableState& s, int k) {
  s.f_ext.setZero();
  if (k >= 200 && k < 500) s.f_ext.col(5) = Eigen::Vector3d(0.0, 2.0, -1.0);
  if (k == 600) {
    s.pinned[17] = 1;
    s.pin_target.col(17) = s.x.col(17) + Eigen::Vector3d(0.0, 0.0, 0.01);
  }
  if (k == 800) s.pinned[17] = 0;
}

// The simd kernel does what the general passes do, up to single-precision forces, through
// gravity, drag, a point load, a held node, the floor and a wall with friction.
TEST(SimdKernel, MatchesTheGeneralPasses) {
  DeformableParams p = small_params(ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler, 3);
  p.kernel = KernelKind::kSimd;
  const DeformableModel m = build_on_floor_by_wall(p);
  DeformableState simd = make_state(m);
  simd.v.row(0).setConstant(0.3);  // thrown at the wall
  simd.centre_v.x() = 0.3;
  DeformableState general = simd;
  double worst_x = 0.0, worst_f = 0.0, worst_centre = 0.0;
  for (int k = 0; k < 1000; ++k) {
    for (DeformableState* s : {&simd, &general}) course_loads(*s, k);
    const StepStatus a = step(m, simd, 1e-3, nullptr);
    const StepStatus b = detail::step_general(m, general, 1e-3, nullptr);
    ASSERT_EQ(a, b) << "step " << k;
    worst_x = std::max(worst_x, (simd.x - general.x).cwiseAbs().maxCoeff());
    worst_centre = std::max(worst_centre, (simd.centre_x - general.centre_x).norm());
    if (a == StepStatus::kOk) {
      worst_f = std::max(worst_f, (simd.force - general.force).cwiseAbs().maxCoeff());
    }
  }
  std::printf("simd vs general, 1000 steps: |dx| %.2e m, |dcentre| %.2e m, |df| %.2e N\n", worst_x,
              worst_centre, worst_f);
  EXPECT_EQ(simd.fault_count, 0u);
  EXPECT_GT(simd.contact_count, 0);
  EXPECT_LT(worst_x, 1e-6);       // [m]
  EXPECT_LT(worst_centre, 1e-6);  // [m]
  EXPECT_LT(worst_f, 1e-3);       // [N] (contact forces reach ~10 N)
}

// The two kernels of a mass-spring body with symplectic Euler differ only in data layout (the
// simd kernel gathers each node's springs in single precision from structure-of-arrays copies,
// the scalar kernel scatters each edge's reaction in double): stepped side by side from the same
// state through gravity, drag, a point load, a held node, the floor and a wall with friction,
// at the paper's level 4 and at level 3, their states, forces and contacts agree to the rounding
// of single-precision spring forces.
TEST(SimdKernel, MatchesTheScalarKernel) {
  for (const int level : {3, 4}) {
    DeformableParams p =
        small_params(ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler, level);
    p.kernel = KernelKind::kScalar;
    const DeformableModel scalar_model = build_on_floor_by_wall(p);
    p.kernel = KernelKind::kSimd;
    const DeformableModel simd_model = build_on_floor_by_wall(p);
    DeformableState scalar = make_state(scalar_model);
    DeformableState simd = make_state(simd_model);  // with the simd kernel's pack
    for (DeformableState* s : {&scalar, &simd}) {
      s->v.row(0).setConstant(0.3);  // thrown at the wall
      s->centre_v.x() = 0.3;
    }
    double worst_x = 0.0, worst_v = 0.0, worst_f = 0.0, worst_plane = 0.0;
    int contact_steps = 0;
    for (int k = 0; k < 1000; ++k) {
      for (DeformableState* s : {&scalar, &simd}) course_loads(*s, k);
      const StepStatus a = step(scalar_model, scalar, 1e-3, nullptr);
      const StepStatus b = step(simd_model, simd, 1e-3, nullptr);
      ASSERT_EQ(a, b) << "level " << level << " step " << k;
      ASSERT_EQ(scalar.contact_count, simd.contact_count) << "level " << level << " step " << k;
      worst_x = std::max(worst_x, (scalar.x - simd.x).cwiseAbs().maxCoeff());
      worst_x = std::max(worst_x, (scalar.centre_x - simd.centre_x).cwiseAbs().maxCoeff());
      worst_v = std::max(worst_v, (scalar.v - simd.v).cwiseAbs().maxCoeff());
      worst_v = std::max(worst_v, (scalar.centre_v - simd.centre_v).cwiseAbs().maxCoeff());
      if (a == StepStatus::kOk) {
        worst_f = std::max(worst_f, (scalar.force - simd.force).cwiseAbs().maxCoeff());
      }
      worst_plane = std::max(worst_plane, (scalar.plane_force_n - simd.plane_force_n).norm());
      contact_steps += scalar.contact_count > 0 ? 1 : 0;
    }
    std::printf(
        "simd vs scalar kernel, level %d, 1000 steps: |dx| %.2e m, |dv| %.2e m/s, "
        "|df| %.2e N, |dF_plane| %.2e N\n",
        level, worst_x, worst_v, worst_f, worst_plane);
    EXPECT_EQ(scalar.fault_count, 0u);
    EXPECT_EQ(simd.fault_count, 0u);
    EXPECT_GT(contact_steps, 500);  // the floor and the wall were exercised
    // about ten times what this machine measures (level 3: 4.5e-8 m, 9.3e-6 m/s, 2.0e-5 N,
    // 3.5e-5 N; level 4, where more nodes slide on the floor and the wall: 5.0e-6 m, 3.1e-4 m/s,
    // 4.1e-5 N, 1.1e-4 N), against a body thrown at 0.3 m/s and contact forces of ~10 N
    const bool fine = level == 3;
    EXPECT_LT(worst_x, fine ? 5e-7 : 5e-5);      // [m]
    EXPECT_LT(worst_v, fine ? 1e-4 : 3e-3);      // [m/s]
    EXPECT_LT(worst_f, fine ? 2e-4 : 4e-4);      // [N]
    EXPECT_LT(worst_plane, fine ? 4e-4 : 1e-3);  // [N]
  }
}

// Within one sub-stepped step the simd kernel packs the next sub-step's positions and velocities
// in its position pass instead of in a pass of its own: the same bits as three single steps of
// a third, through a throw at the floor and wall, a point load, and a body falling asleep and
// being woken by a load. (Held nodes take the per-node pass, which packs for itself; step()
// also moves their targets in equal shares over the sub-steps, so they are not compared here.)
TEST(SimdKernel, FusedPackOfSubStepsIsBitIdenticalToSingleSteps) {
  DeformableParams p = small_params(ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler, 3);
  p.kernel = KernelKind::kSimd;
  p.min_substeps = 3;
  p.sleep_time_s = 0.05;
  p.sleep_speed_mps = 0.05;
  const DeformableModel m = build_on_floor_by_wall(p);
  ASSERT_EQ(m.substeps_for(1e-3), 3);
  DeformableState a = make_state(m);
  a.v.row(0).setConstant(0.3);
  a.centre_v.x() = 0.3;
  DeformableState b = a;
  const double h = 1e-3 / 3;
  int slept = 0, woke = 0;
  for (int k = 0; k < 3000; ++k) {
    for (DeformableState* s : {&a, &b}) {
      s->f_ext.setZero();
      if (k >= 200 && k < 500) s->f_ext.col(5) = Eigen::Vector3d(0.0, 2.0, -1.0);
      if (k == 2500) s->f_ext.col(7) = Eigen::Vector3d(0.0, 0.0, -3.0);  // wakes it
    }
    const StepStatus sa = step(m, a, 1e-3, nullptr);
    StepStatus sb = StepStatus::kOk;
    for (int j = 0; j < 3; ++j) {
      sb = detail::step_once(m, b, h, nullptr);
      if (sb == StepStatus::kSleeping) {
        b.sim_time_s += (2 - j) * h;  // step() sleeps through the rest of the call
        break;
      }
    }
    if (sa != StepStatus::kSleeping) {
      ASSERT_EQ(sa, sb) << k;
    }
    woke += slept > 0 && !a.sleeping ? 1 : 0;
    slept += a.sleeping ? 1 : 0;
    ASSERT_TRUE(a.x == b.x) << k;
    ASSERT_TRUE(a.v == b.v) << k;
    ASSERT_TRUE(a.centre_x == b.centre_x) << k;
    ASSERT_TRUE(a.centre_v == b.centre_v) << k;
    ASSERT_FALSE(a.simd_pack_fresh) << k;  // never outlives a step() call
  }
  EXPECT_GT(slept, 0);  // it did fall asleep, and the load at 2500 woke it
  EXPECT_GT(woke, 0);
  EXPECT_EQ(a.fault_count, 0u);
}

// Same rules as the other kernels: no allocation, deterministic, momentum of a free body kept.
TEST(SimdKernel, AllocatesNothingAndIsDeterministic) {
  DeformableParams p = small_params(ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler, 4);
  p.kernel = KernelKind::kSimd;
  const DeformableModel m = build(p);
  DeformableState a = make_state(m);
  displace_radially(m, a, 0, 0.005);
  a.v.row(1).setConstant(0.2);
  a.centre_v.y() = 0.2;
  DeformableState b = a;
  step(m, a, 1e-3, nullptr);
  step(m, b, 1e-3, nullptr);
  {
    teleop::test::NoAllocScope scope;
    for (int k = 0; k < 100; ++k) step(m, a, 1e-3, nullptr);
    EXPECT_EQ(scope.allocations(), 0u);
  }
  for (int k = 0; k < 100; ++k) step(m, b, 1e-3, nullptr);
  EXPECT_TRUE(a.x == b.x);
  EXPECT_TRUE(a.v == b.v);
  const double py = a.v.row(1).dot(m.mass_kg) + m.centre_mass_kg * a.centre_v.y();
  EXPECT_NEAR(py / m.total_mass_kg, 0.2, 1e-6);
}

}  // namespace
