#pragma once
// Internal: the node update of server/deformable/: integrate (integrators.cpp) for the surface
// models' general passes, and the per-node pieces the other passes share: the symplectic-Euler
// update of one node (both fused mass-spring kernels) and the end of a step (held nodes onto
// their targets, the post-step sums; the general passes and the fem model). Not part of the
// deformable API.
#include <cstddef>

#include "server/deformable/kernels.hpp"
#include "server/deformable/plane_contact.hpp"

namespace teleop::sim::deformable::detail {

/// Advances the nodes of a surface model (and its centre node) by h [s] with the integrator of
/// m.params on the forces in s.work_f; contact impulses for explicit and symplectic Euler.
/// Allocates nothing.
void integrate(const DeformableModel& m, DeformableState& s, double h);

/// The post-step sums of a kernel that advances its nodes one at a time (see KernelSums).
struct NodeSums {
  double fastest2 = 0.0, sum_x = 0.0, sum_v = 0.0, mx = 0.0, my = 0.0, mz = 0.0;

  /// Adds a node of mass mi [kg] now at (px, py, pz) [m] moving at (vx, vy, vz) [m/s].
  TELEOP_ALWAYS_INLINE void add(double mi, double px, double py, double pz, double vx, double vy,
                                double vz) {
    const double sp2 = vx * vx + vy * vy + vz * vz;
    fastest2 = sp2 > fastest2 ? sp2 : fastest2;
    sum_x += px + py + pz;
    sum_v += sp2;  // NaN and infinity propagate into the sums
    mx += mi * px;
    my += mi * py;
    mz += mi * pz;
  }

  TELEOP_ALWAYS_INLINE void store(KernelSums& out) const {
    out.fastest2 = fastest2;
    out.sum_x = sum_x;
    out.sum_v = sum_v;
    out.mx[0] = mx;
    out.mx[1] = my;
    out.mx[2] = mz;
  }
};

/// Symplectic Euler of node i (mass mi [kg], 1 / mass inv_m) at (xx, xy, xz) moving at
/// (vx, vy, vz) under the total force (fx, fy, fz) [N], the plane springs included (`touched`,
/// `spring_of` from node_plane_springs): v += h f / m, the contact impulses (node_impulses), then
/// x += h v; a held node keeps its velocity and goes to its target `target` (3 doubles). Writes
/// the node's x and v into the 3 x N arrays x and v, adds the planes' forces to plane_force and
/// the node to sums.
TELEOP_ALWAYS_INLINE void symplectic_node(const DeformableModel& m, int i, double h, double mi,
                                          double inv_m, bool held, const double* target, double xx,
                                          double xy, double xz, double vx, double vy, double vz,
                                          double fx, double fy, double fz, unsigned touched,
                                          const double spring_of[8], double* __restrict x,
                                          double* __restrict v, Eigen::Vector3d& plane_force,
                                          NodeSums& sums) {
  double px, py, pz;
  if (!held) {
    const double hm = h * inv_m;
    vx += hm * fx;
    vy += hm * fy;
    vz += hm * fz;
    node_impulses(m, i, mi, h, touched, spring_of, vx, vy, vz, plane_force);
    px = xx + h * vx;
    py = xy + h * vy;
    pz = xz + h * vz;
  } else {
    px = target[0];
    py = target[1];
    pz = target[2];
  }
  const int a = 3 * i;
  v[a] = vx;
  v[a + 1] = vy;
  v[a + 2] = vz;
  x[a] = px;
  x[a + 1] = py;
  x[a + 2] = pz;
  sums.add(mi, px, py, pz, vx, vy, vz);
}

/// Symplectic Euler of the centre node (velocity cv [m/s] at the step's start) under gravity,
/// the drag relative to the body's mean velocity vm [m/s] and the radial springs' reaction fc
/// [N] (both fused mass-spring kernels).
TELEOP_ALWAYS_INLINE void symplectic_centre(const DeformableModel& m, DeformableState& s, double h,
                                            const double cv[3], const double vm[3],
                                            const double fc[3]) {
  const DeformableParams& p = m.params;
  const double alpha = p.mass_damping_per_s;
  const double gx = p.gravity_mps2.x(), gy = p.gravity_mps2.y(), gz = p.gravity_mps2.z();
  const double hm = h / m.centre_mass_kg, mc = m.centre_mass_kg;
  s.centre_v.x() += hm * (mc * (gx - alpha * (cv[0] - vm[0])) + fc[0]);
  s.centre_v.y() += hm * (mc * (gy - alpha * (cv[1] - vm[1])) + fc[1]);
  s.centre_v.z() += hm * (mc * (gz - alpha * (cv[2] - vm[2])) + fc[2]);
  s.centre_x += h * s.centre_v;
}

/// The end of a step of the first n nodes (masses `mass` [kg]): held nodes onto their targets,
/// then the post-step sums into `sums`.
TELEOP_ALWAYS_INLINE void hold_and_sum(const Eigen::VectorXd& mass, int n, DeformableState& s,
                                       KernelSums& sums) {
  double fastest2 = 0.0, sum_x = 0.0, sum_v = 0.0;
  Eigen::Vector3d mx = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    if (s.pinned_count > 0 && s.pinned[static_cast<std::size_t>(i)]) {
      s.x.col(i) = s.pin_target.col(i);
    }
    const double sp2 = s.v.col(i).squaredNorm();
    fastest2 = sp2 > fastest2 ? sp2 : fastest2;
    sum_x += s.x.col(i).sum();
    sum_v += sp2;  // NaN and infinity propagate into the sums
    mx += mass(i) * s.x.col(i);
  }
  sums.fastest2 = fastest2;
  sums.sum_x = sum_x;
  sums.sum_v = sum_v;
  sums.mx[0] = mx.x();
  sums.mx[1] = mx.y();
  sums.mx[2] = mx.z();
}

}  // namespace teleop::sim::deformable::detail
