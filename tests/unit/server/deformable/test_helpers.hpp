#pragma once
// Shared helpers of the deformable-body tests.
#include <Eigen/Eigenvalues>
#include <random>

#include "server/deformable/deformable.hpp"

namespace teleop::sim::deformable::testing {

/// A small sphere (radius 0.25 m, centre at the origin), zero gravity, no planes.
inline DeformableParams small_params(ModelKind model, IntegratorKind integrator, int level) {
  DeformableParams p;
  p.model = model;
  p.integrator = integrator;
  p.level = level;
  p.centre_m.setZero();
  p.gravity_mps2.setZero();
  if (model != ModelKind::kMassSpring) p.radial_stiffness_n_per_m3 = 0.0;
  p.sleep_time_s = 1e9;  // tests of dynamics never sleep
  return p;
}

/// Switches every damper off (springs, radial springs, drag).
inline void make_undamped(DeformableParams& p) {
  p.stiffness_damping_s = 0.0;
  p.radial_damping_s = 0.0;
  p.mass_damping_per_s = 0.0;
}

inline DeformableModel build(const DeformableParams& p, const std::vector<Plane>& planes = {}) {
  return make_model(make_mesh_for(p), p, planes);
}

/// The kernels' obstacle course: gravity, the body 1 cm above a floor with friction 0.4, and a
/// wall at x = 0.27 m (facing -x) 2 cm from its side; returns the model built on them.
inline DeformableModel build_on_floor_by_wall(DeformableParams p) {
  p.gravity_mps2 = Eigen::Vector3d(0, 0, -9.81);
  p.centre_m = Eigen::Vector3d(0.0, 0.0, 0.26);
  Plane floor;
  floor.friction = 0.4;
  Plane wall;
  wall.normal = Eigen::Vector3d(-1, 0, 0);
  wall.offset_m = -0.27;
  return build(p, {floor, wall});
}

/// Largest deviation of the shape from the rest shape, translation removed [m].
inline double shape_error(const DeformableModel& m, const DeformableState& s) {
  const Eigen::Vector3d c = s.x.rowwise().mean();
  const Eigen::Vector3d c0 = m.mesh.vertices.rowwise().mean();
  double worst = 0.0;
  for (int i = 0; i < m.node_count; ++i) {
    worst = std::max(worst, ((s.x.col(i) - c) - (m.mesh.vertices.col(i) - c0)).norm());
  }
  return worst;
}

/// Moves node i radially (from the rest centre) by `delta_m` (positive: outward).
inline void displace_radially(const DeformableModel& m, DeformableState& s, int i, double delta_m) {
  const Eigen::Vector3d u = (s.x.col(i) - m.rest_centre_m).normalized();
  s.x.col(i) += delta_m * u;
}

/// Linearised stiffness K = -df/dx at the current state by central differences of
/// internal_forces (damping off in the model), dofs 3N (+3 for the centre node).
inline Eigen::MatrixXd stiffness_fd(const DeformableModel& m, DeformableState s) {
  const int n = m.node_count;
  const int dofs = 3 * n + (m.has_centre ? 3 : 0);
  Eigen::MatrixXd k(dofs, dofs);
  Eigen::Matrix3Xd f;
  const double eps = 1e-7;
  auto forces = [&](Eigen::VectorXd& out) {
    internal_forces(m, s, f);
    out.resize(dofs);
    for (int i = 0; i < n; ++i) out.segment<3>(3 * i) = f.col(i);
    if (m.has_centre) out.segment<3>(3 * n) = s.work_f.col(n);
  };
  Eigen::VectorXd fp, fm;
  for (int d = 0; d < dofs; ++d) {
    double& coord = d < 3 * n ? s.x(d % 3, d / 3) : s.centre_x(d - 3 * n);
    const double keep = coord;
    coord = keep + eps;
    forces(fp);
    coord = keep - eps;
    forces(fm);
    coord = keep;
    k.col(d) = -(fp - fm) / (2 * eps);
  }
  return k;
}

/// Largest angular frequency of the linearised body, sqrt(lambda_max(M^-1/2 K M^-1/2)).
inline double omega_max(const DeformableModel& m, const DeformableState& s) {
  const Eigen::MatrixXd k = stiffness_fd(m, s);
  const int n = m.node_count;
  Eigen::VectorXd minv_sqrt(k.rows());
  for (int i = 0; i < n; ++i)
    minv_sqrt.segment<3>(3 * i).setConstant(1.0 / std::sqrt(m.mass_kg(i)));
  if (m.has_centre) minv_sqrt.tail<3>().setConstant(1.0 / std::sqrt(m.centre_mass_kg));
  Eigen::MatrixXd a = minv_sqrt.asDiagonal() * k * minv_sqrt.asDiagonal();
  a = 0.5 * (a + a.transpose()).eval();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(a, Eigen::EigenvaluesOnly);
  return std::sqrt(es.eigenvalues().maxCoeff());
}

/// Adds a seeded random displacement of amplitude `amp_m` to every node (and the centre).
inline void perturb(DeformableState& s, double amp_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amp_m, amp_m);
  for (int i = 0; i < s.x.cols(); ++i) {
    for (int d = 0; d < 3; ++d) s.x(d, i) += u(rng);
  }
  for (int d = 0; d < 3; ++d) s.centre_x(d) += u(rng);
}

}  // namespace teleop::sim::deformable::testing
