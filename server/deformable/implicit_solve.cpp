// The implicit solve of the surface models (mass_spring, navier_linear, navier_corotational):
// one Newton step of backward Euler (Baraff and Witkin 1998),
//   (M + h C + h^2 K) dv = h (f - h K v),
// with K and C the per-edge, radial and contact 3 x 3 blocks compute_forces stored
// (flags.jacobian), solved by conjugate_gradient (conjugate_gradient.hpp, the same routine as the
// fem model's). Nothing here allocates.
#include <cstddef>

#include "server/deformable/conjugate_gradient.hpp"
#include "server/deformable/kernels.hpp"

namespace teleop::sim::deformable::detail {

namespace {

// out = mc * M p + cc * C p + kc * K p, where K and C are the (positive semi-definite)
// stiffness and damping blocks stored by compute_forces(jacobian = true). Column N is the
// centre node. Pinned nodes are held: their rows and columns are dropped.
TELEOP_HOT_CLONES
void apply_system(const DeformableModel& m, const DeformableState& s, const Eigen::Matrix3Xd& pv,
                  Eigen::Matrix3Xd& out, double mc, double cc, double kc) {
  const int n = m.node_count;
  const double drag = cc * m.params.mass_damping_per_s;
  for (int i = 0; i < n; ++i) out.col(i) = (mc + drag) * m.mass_kg(i) * pv.col(i);
  out.col(n) = (mc + drag) * m.centre_mass_kg * pv.col(n);
  const int ne = static_cast<int>(m.edges.cols());
  for (int e = 0; e < ne; ++e) {
    const int i = m.edges(0, e), j = m.edges(1, e);
    const Eigen::Vector4d co = s.edge_coef.col(e);
    const Eigen::Vector3d w = s.edge_dir.col(e);
    const double si = cc * co(2) + kc * co(0), sd = cc * co(3) + kc * co(1);
    const Eigen::Vector3d d = pv.col(i) - pv.col(j);
    const Eigen::Vector3d y = si * d + (sd * w.dot(d)) * w;
    out.col(i) += y;
    out.col(j) -= y;
  }
  if (m.has_centre) {
    Eigen::Vector3d yc = Eigen::Vector3d::Zero();
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector4d co = s.radial_coef.col(i);
      const Eigen::Vector3d w = s.radial_dir.col(i);
      const double si = cc * co(2) + kc * co(0), sd = cc * co(3) + kc * co(1);
      const Eigen::Vector3d d = pv.col(i) - pv.col(n);
      const Eigen::Vector3d y = si * d + (sd * w.dot(d)) * w;
      out.col(i) += y;
      yc -= y;
    }
    out.col(n) += yc;
  }
  for (int c = 0; c < s.contact_count; ++c) {
    const int i = s.contact_node[static_cast<std::size_t>(c)];
    const Eigen::Vector3d nrm = s.contact_normal.col(c);
    const double sc = cc * s.contact_coef(1, c) + kc * s.contact_coef(0, c);
    out.col(i) += (sc * nrm.dot(pv.col(i))) * nrm;
  }
  if (s.pinned_count > 0) {
    for (int i = 0; i < n; ++i) {
      if (s.pinned[static_cast<std::size_t>(i)]) out.col(i).setZero();
    }
  }
}

// Jacobi preconditioner: the inverse of the diagonal of M + h C + h^2 K, into s.work_diag.
TELEOP_HOT_CLONES
void system_diagonal(const DeformableModel& m, DeformableState& s, double h) {
  const int n = m.node_count;
  Eigen::Matrix3Xd& dg = s.work_diag;
  const double drag = 1.0 + h * m.params.mass_damping_per_s;
  for (int i = 0; i < n; ++i) dg.col(i).setConstant(drag * m.mass_kg(i));
  dg.col(n).setConstant(drag * m.centre_mass_kg);
  const double h2 = h * h;
  for (int e = 0; e < m.edges.cols(); ++e) {
    const Eigen::Vector4d co = s.edge_coef.col(e);
    const Eigen::Vector3d w = s.edge_dir.col(e);
    const Eigen::Vector3d dd = Eigen::Vector3d::Constant(h * co(2) + h2 * co(0)) +
                               (h * co(3) + h2 * co(1)) * w.cwiseProduct(w);
    dg.col(m.edges(0, e)) += dd;
    dg.col(m.edges(1, e)) += dd;
  }
  if (m.has_centre) {
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector4d co = s.radial_coef.col(i);
      const Eigen::Vector3d w = s.radial_dir.col(i);
      const Eigen::Vector3d dd = Eigen::Vector3d::Constant(h * co(2) + h2 * co(0)) +
                                 (h * co(3) + h2 * co(1)) * w.cwiseProduct(w);
      dg.col(i) += dd;
      dg.col(n) += dd;
    }
  }
  for (int c = 0; c < s.contact_count; ++c) {
    const Eigen::Vector3d nrm = s.contact_normal.col(c);
    dg.col(s.contact_node[static_cast<std::size_t>(c)]) +=
        (h * s.contact_coef(1, c) + h2 * s.contact_coef(0, c)) * nrm.cwiseProduct(nrm);
  }
  if (!m.has_centre) dg.col(n).setOnes();  // unused column: keep it well defined
  dg = dg.cwiseInverse();                  // stored inverted: CG multiplies
}

}  // namespace

TELEOP_HOT_CLONES
void implicit_velocity_change(const DeformableModel& m, DeformableState& s, double h) {
  const int n = m.node_count;
  Eigen::Matrix3Xd& vfull = s.work_z;  // temporarily: velocities incl. centre
  vfull.leftCols(n) = s.v;
  vfull.col(n) = s.centre_v;
  apply_system(m, s, vfull, s.work_ap, 0.0, 0.0, 1.0);  // K v
  Eigen::Matrix3Xd& b = s.work_b;
  b = h * (s.work_f - h * s.work_ap);
  for (int i = 0; i < n; ++i) {
    if (s.pinned[static_cast<std::size_t>(i)]) b.col(i).setZero();
  }
  if (!m.has_centre) b.col(n).setZero();
  system_diagonal(m, s, h);
  const double h2 = h * h;
  conjugate_gradient(m, s, n + 1, [&](const Eigen::Matrix3Xd& p, Eigen::Matrix3Xd& out) {
    apply_system(m, s, p, out, 1.0, h, h2);
  });
}

}  // namespace teleop::sim::deformable::detail
