#pragma once
// Internal: the linear solve of implicit Euler in server/deformable/, shared by the surface models
// (implicit_solve.cpp) and the volumetric FEM (fem.cpp). Not part of the deformable API.
#include <algorithm>
#include <cmath>

#include "server/deformable/kernels.hpp"

namespace teleop::sim::deformable::detail {

/// Jacobi-preconditioned conjugate gradients for A dv = b on the first `cols` columns of the
/// state's 3 x N scratch fields: b in s.work_b, the preconditioner 1 / diag(A) in s.work_diag,
/// the solution (from zero) into s.work_dv; s.work_r, s.work_z, s.work_p and s.work_ap are
/// scratch. `system(p, out)` sets out = A p (A symmetric positive definite, 3 x N fields, its
/// columns from `cols` on unused). Stops after m.params.cg_max_iterations iterations, when the
/// preconditioned residual r.z has fallen to cg_tolerance^2 of its start, or when p.A p is not
/// positive; the count and the relative residual go to s.cg_iterations and s.cg_residual.
/// A template on the system, so that its product inlines into the caller's loop and nothing is
/// allocated (the columns are views of the state's fields).
template <class System>
TELEOP_ALWAYS_INLINE void conjugate_gradient(const DeformableModel& m, DeformableState& s, int cols,
                                             const System& system) {
  auto b = s.work_b.leftCols(cols);
  auto inv_diag = s.work_diag.leftCols(cols);
  auto dv = s.work_dv.leftCols(cols);
  auto r = s.work_r.leftCols(cols);
  auto z = s.work_z.leftCols(cols);
  auto pp = s.work_p.leftCols(cols);
  auto ap = s.work_ap.leftCols(cols);
  dv.setZero();
  r = b;
  z = r.cwiseProduct(inv_diag);
  pp = z;
  double rz = (r.array() * z.array()).sum();
  const double rz0 = rz;
  const double tol2 = m.params.cg_tolerance * m.params.cg_tolerance;
  int it = 0;
  while (it < m.params.cg_max_iterations && rz > tol2 * rz0 && rz0 > 0.0) {
    system(s.work_p, s.work_ap);
    const double pap = (pp.array() * ap.array()).sum();
    if (!(pap > 0.0)) break;
    const double alpha = rz / pap;
    dv += alpha * pp;
    r -= alpha * ap;
    z = r.cwiseProduct(inv_diag);
    const double rz_new = (r.array() * z.array()).sum();
    pp = z + (rz_new / rz) * pp;
    rz = rz_new;
    ++it;
  }
  s.cg_iterations = it;
  s.cg_residual = rz0 > 0.0 ? std::sqrt(std::max(rz, 0.0) / rz0) : 0.0;
}

}  // namespace teleop::sim::deformable::detail
