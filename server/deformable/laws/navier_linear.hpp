#pragma once
// Internal: the finite-difference Navier law with linear strain (model navier_linear, the
// paper's eq. (2)) of server/deformable/. Per edge (i, j) with rest vector D = X_j - X_i and rest
// direction u0: g = (x_j - x_i) - D + beta (v_j - v_i) and the force on i
//   f = a g + b (g . u0) u0,
// a = edge_k_iso (the Laplacian term, mu) and b = edge_k_dir (the grad-div term, lambda + mu),
// both weighted by the nodes' volumes over their rest lengths (model.cpp). Not part of the
// deformable API.
#include "server/deformable/kernels.hpp"

namespace teleop::sim::deformable::detail {

/// Linear Navier edge forces into s.edge_force (the force on each edge's first node), and with
/// flags.jacobian the implicit blocks (s.edge_dir, s.edge_coef).
TELEOP_ALWAYS_INLINE void navier_linear_edge_forces(const DeformableModel& m, DeformableState& s,
                                                    ForceFlags flags) {
  const int ne = static_cast<int>(m.edges.cols());
  const Eigen::Matrix3Xd& x = s.x;
  const Eigen::Matrix3Xd& v = s.v;
  const Eigen::Matrix3Xd& X = m.mesh.vertices;
  const double beta = m.params.stiffness_damping_s;
  for (int e = 0; e < ne; ++e) {
    const int i = m.edges(0, e), j = m.edges(1, e);
    const Eigen::Vector3d u0 = m.rest_dir.col(e);
    const Eigen::Vector3d strain = (x.col(j) - x.col(i)) - (X.col(j) - X.col(i));
    const Eigen::Vector3d g = strain + beta * (v.col(j) - v.col(i));
    const double a = m.edge_k_iso(e), b = m.edge_k_dir(e);
    const Eigen::Vector3d f = a * g + (b * g.dot(u0)) * u0;
    s.edge_force.col(e) = f;
    if (flags.jacobian) {
      s.edge_dir.col(e) = u0;
      s.edge_coef.col(e) << a, b, beta * a, beta * b;
    }
  }
}

}  // namespace teleop::sim::deformable::detail
