#pragma once
// Internal: node-plane contact of the surface models (mass_spring, navier_linear,
// navier_corotational) of server/deformable/; the fem model's implicit node contact is in
// fem.cpp. Node i inside plane k (depth d = offset - n . x_i > 0) feels a penalty spring
// k_i d along the plane's normal, a damper c_i on its normal velocity and Coulomb friction mu:
// - implicit Euler: spring, damping and (rate-limited) friction as forces (add_plane_contacts
//   with flags.jacobian), the damping also in the system matrix (implicit_solve.cpp);
// - explicit and symplectic Euler: the spring as a force, the damping and friction as velocity
//   impulses after the velocity update (contact_impulse), implicit in the damping and so stable
//   for any damping ratio (an explicit damper on a light node next to the stability limit of the
//   membrane would not be).
// Both kernels and the general passes use these functions. Not part of the deformable API.
#include <algorithm>
#include <cmath>
#include <cstddef>

#include "server/deformable/kernels.hpp"

namespace teleop::sim::deformable::detail {

/// Node-plane penalty contact: records every contact (s.contact_*) and adds its force to
/// s.work_f; with flags.jacobian also its damping and friction (see the file's comment), summed
/// into s.plane_force_n.
TELEOP_ALWAYS_INLINE void add_plane_contacts(const DeformableModel& m, DeformableState& s, double h,
                                             ForceFlags flags) {
  const int n = m.node_count;
  const DeformableParams& p = m.params;
  Eigen::Matrix3Xd& F = s.work_f;
  const Eigen::Matrix3Xd& x = s.x;
  const Eigen::Matrix3Xd& v = s.v;
  int nc = 0;
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < m.plane_count; ++k) {
      const Plane& pl = m.planes[static_cast<std::size_t>(k)];
      const double dist = pl.normal.dot(x.col(i)) - pl.offset_m;
      if (dist >= 0.0) continue;
      const double spring = -m.contact_k(i) * dist;
      s.contact_node[static_cast<std::size_t>(nc)] = i;
      s.contact_normal.col(nc) = pl.normal;
      s.contact_coef.col(nc) << m.contact_k(i), m.contact_c(i), spring,
          p.friction ? pl.friction : 0.0;
      ++nc;
      if (!flags.jacobian) {
        F.col(i) += spring * pl.normal;
        continue;
      }
      const Eigen::Vector3d vi = v.col(i);
      const double vn = pl.normal.dot(vi);
      double fn = spring - m.contact_c(i) * vn;
      if (fn < 0.0) fn = 0.0;  // a wall pushes, never pulls
      Eigen::Vector3d f = fn * pl.normal;
      if (p.friction && pl.friction > 0.0) {
        const Eigen::Vector3d vt = vi - vn * pl.normal;
        const double st = vt.norm();
        if (st > 1e-12) {
          const double ft = std::min(pl.friction * fn, 0.5 * m.mass_kg(i) * st / h);
          f -= (ft / st) * vt;
        }
      }
      F.col(i) += f;
      s.plane_force_n += f;
    }
  }
  s.contact_count = nc;
}

/// One contact's damping and friction as an impulse on a node of mass `mass` [kg] moving at
/// (vx, vy, vz) [m/s], after its velocity update, against a plane of unit normal `nrm`, damper
/// `damping` [N s/m], the spring's impulse h k d [N s] and friction `mu`:
///   v_n <- v_n / (1 + h c / m), never pulling (total normal impulse >= 0);
///   tangential impulse <= mu * normal impulse, and never more than stops the sliding.
/// Updates the velocity and adds the plane's force (impulse / h) to `total`.
TELEOP_ALWAYS_INLINE void contact_impulse(const Eigen::Vector3d& nrm, double mass, double damping,
                                          double spring_impulse, double mu, double h, double& vx,
                                          double& vy, double& vz, Eigen::Vector3d& total) {
  Eigen::Vector3d vi(vx, vy, vz);
  const double vn = nrm.dot(vi);
  double dvn = vn / (1.0 + h * damping / mass) - vn;
  dvn = std::max(dvn, -spring_impulse / mass);
  vi += dvn * nrm;
  const double jn = spring_impulse + mass * dvn;  // >= 0
  Eigen::Vector3d impulse = jn * nrm;
  if (mu > 0.0) {
    const Eigen::Vector3d vt = vi - nrm.dot(vi) * nrm;
    const double st = vt.norm();
    if (st > 1e-12) {
      const double jt = std::min(mu * jn, mass * st);
      vi -= (jt / (mass * st)) * vt;
      impulse -= (jt / st) * vt;
    }
  }
  total += impulse / h;
  vx = vi.x();
  vy = vi.y();
  vz = vi.z();
}

/// The impulses of the contacts recorded by add_plane_contacts on s.v (held nodes keep their
/// velocity), their forces added to s.plane_force_n (explicit and symplectic Euler).
TELEOP_ALWAYS_INLINE void apply_contact_impulses(const DeformableModel& m, DeformableState& s,
                                                 double h) {
  for (int c = 0; c < s.contact_count; ++c) {
    const int i = s.contact_node[static_cast<std::size_t>(c)];
    if (s.pinned_count > 0 && s.pinned[static_cast<std::size_t>(i)]) continue;
    double vx = s.v(0, i), vy = s.v(1, i), vz = s.v(2, i);
    contact_impulse(s.contact_normal.col(c), m.mass_kg(i), s.contact_coef(1, c),
                    h * s.contact_coef(2, c), s.contact_coef(3, c), h, vx, vy, vz, s.plane_force_n);
    s.v(0, i) = vx;
    s.v(1, i) = vy;
    s.v(2, i) = vz;
  }
}

/// The plane penalty springs of node i at (xx, xy, xz), for the kernels that advance one node at
/// a time: their force added to (fx, fy, fz), each spring force into spring_of[k], the count
/// into nc; returns the planes touched (bit k: inside plane k).
TELEOP_ALWAYS_INLINE unsigned node_plane_springs(const DeformableModel& m, int i, double xx,
                                                 double xy, double xz, double spring_of[8],
                                                 double& fx, double& fy, double& fz, int& nc) {
  const double* __restrict ck = m.contact_k.data();
  unsigned touched = 0;
  for (int k = 0; k < m.plane_count; ++k) {
    const Plane& pl = m.planes[static_cast<std::size_t>(k)];
    const double dist = pl.normal.x() * xx + pl.normal.y() * xy + pl.normal.z() * xz - pl.offset_m;
    if (dist >= 0.0) continue;
    spring_of[k] = -ck[i] * dist;
    fx += spring_of[k] * pl.normal.x();
    fy += spring_of[k] * pl.normal.y();
    fz += spring_of[k] * pl.normal.z();
    touched |= 1u << k;
    ++nc;
  }
  return touched;
}

/// The contact impulses of node i (mass mi) on the planes node_plane_springs found (`touched`,
/// `spring_of`), applied to (vx, vy, vz) in plane order; the planes' forces added to plane_force.
TELEOP_ALWAYS_INLINE void node_impulses(const DeformableModel& m, int i, double mi, double h,
                                        unsigned touched, const double spring_of[8], double& vx,
                                        double& vy, double& vz, Eigen::Vector3d& plane_force) {
  const double* __restrict cc = m.contact_c.data();
  for (int k = 0; touched != 0 && k < m.plane_count; ++k) {
    if ((touched & (1u << k)) == 0) continue;
    const Plane& pl = m.planes[static_cast<std::size_t>(k)];
    contact_impulse(pl.normal, mi, cc[i], h * spring_of[k], m.params.friction ? pl.friction : 0.0,
                    h, vx, vy, vz, plane_force);
  }
}

}  // namespace teleop::sim::deformable::detail
