#pragma once
// Internal: the rotational part of a 3x3 matrix (polar decomposition), shared by every
// co-rotated force law of server/deformable/ (the surface Navier model's node frames and the
// volumetric FEM's element frames). Header-only so that it inlines into each hot loop and each
// of its instruction-set clones. Not part of the deformable API.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "server/deformable/hot.hpp"

namespace teleop::sim::deformable::detail {

// Four doubles per vector (GCC's vector extensions: AVX2 in the x86-64-v3 clone, two SSE2 halves
// in the baseline one), for the co-rotational passes below.
// (the helpers are always inlined: no vector crosses a call, whatever -Wpsabi says of the ABI)
#pragma GCC diagnostic ignored "-Wpsabi"
typedef double V4 __attribute__((vector_size(32)));
typedef double V4u __attribute__((vector_size(32), aligned(8), may_alias));

TELEOP_ALWAYS_INLINE V4 load4(const double* p) { return *reinterpret_cast<const V4u*>(p); }
TELEOP_ALWAYS_INLINE void store4(double* p, V4 v) { *reinterpret_cast<V4u*>(p) = v; }
typedef long long V4i __attribute__((vector_size(32)));

// Rotation matrix of the unit quaternion (w, x, y, z), column-major into r[9]: of one node
// (T = double) or of four (T = V4, one node per lane).
template <class T>
TELEOP_ALWAYS_INLINE void quaternion_matrix(T w, T x, T y, T z, T* r) {
  const T tx = 2.0 * x, ty = 2.0 * y, tz = 2.0 * z;
  const T twx = tx * w, twy = ty * w, twz = tz * w;
  const T txx = tx * x, txy = ty * x, txz = tz * x;
  const T tyy = ty * y, tyz = tz * y, tzz = tz * z;
  r[0] = 1.0 - (tyy + tzz);
  r[1] = txy + twz;
  r[2] = txz - twy;
  r[3] = txy - twz;
  r[4] = 1.0 - (txx + tzz);
  r[5] = tyz + twx;
  r[6] = txz + twy;
  r[7] = tyz - twx;
  r[8] = 1.0 - (txx + tyy);
}

TELEOP_ALWAYS_INLINE double abs_of(double x) { return std::fabs(x); }
TELEOP_ALWAYS_INLINE V4 abs_of(V4 x) {
  for (int l = 0; l < 4; ++l) x[l] = std::fabs(x[l]);
  return x;
}

// The step d of extract_rotation from the frame r (the matrix of q) for the ring matrix a (both
// column-major): Newton's where H is positive definite (`newton` set), else Mueller's. One node
// (T = double, B = bool) or four (T = V4, B = V4i, one node per lane).
template <class T, class B>
TELEOP_ALWAYS_INLINE void rotation_step(const T* a, const T* r, T& ox, T& oy, T& oz, B& newton) {
  // C = A R^T: C_ij = sum_k A_ik R_jk
  T c[3][3];
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) c[i][j] = a[i] * r[j] + a[3 + i] * r[3 + j] + a[6 + i] * r[6 + j];
  }
  const T gx = c[2][1] - c[1][2], gy = c[0][2] - c[2][0], gz = c[1][0] - c[0][1];
  const T tr = c[0][0] + c[1][1] + c[2][2];
  const T h00 = tr - c[0][0], h11 = tr - c[1][1], h22 = tr - c[2][2];
  const T h01 = -0.5 * (c[0][1] + c[1][0]), h02 = -0.5 * (c[0][2] + c[2][0]),
          h12 = -0.5 * (c[1][2] + c[2][1]);
  // adjugate of the symmetric H, and its determinant
  const T m00 = h11 * h22 - h12 * h12, m01 = h02 * h12 - h01 * h22, m02 = h01 * h12 - h02 * h11,
          m11 = h00 * h22 - h02 * h02, m12 = h01 * h02 - h00 * h12, m22 = h00 * h11 - h01 * h01;
  const T det = h00 * m00 + h01 * m01 + h02 * m02;
  newton = (h00 > 0.0) & (m22 > 0.0) & (det > 1e-9 * tr * tr * tr);
  // one division: by det for a Newton step, by |tr C| for Mueller's
  const T inv = 1.0 / (newton ? det : abs_of(tr) + 1e-12);
  ox = (newton ? m00 * gx + m01 * gy + m02 * gz : gx) * inv;
  oy = (newton ? m01 * gx + m11 * gy + m12 * gz : gy) * inv;
  oz = (newton ? m02 * gx + m12 * gy + m22 * gz : gz) * inv;
}

// Rotational part of A (a[9], column-major; polar decomposition), warm-started from q (r[9]
// holding its matrix, column-major, on entry) and written to q and r. It maximises tr(R^T A) (as
// Mueller et al. 2016, "A robust method to extract the rotational part of deformations"), by Newton
// steps: with R <- exp([d]x) R, C = A R^T, tr(R^T A) ~ tr C + g . d - d^T H d / 2 for g = (C21 -
// C12, C02 - C20, C10 - C01) and H = tr(C) I - sym(C), so d = H^-1 g (quadratic convergence: one or
// two steps from the last frame). Where H is not positive definite (far from the maximum) the step
// is Mueller's, d = g / |tr C| (an ascent step). It stops when a step is below the tolerance, or
// after a Newton step whose square is (its remaining error). Plain scalar arithmetic; the matrix of
// the last check is the result when it converged.
TELEOP_ALWAYS_INLINE void extract_rotation(const double* a, Eigen::Quaterniond& q_io,
                                           int max_iterations, double tolerance_rad, double* r) {
  double qw = q_io.w(), qx = q_io.x(), qy = q_io.y(), qz = q_io.z();
  bool converged = false;
  for (int it = 0; it < max_iterations; ++it) {
    if (it > 0) quaternion_matrix(qw, qx, qy, qz, r);  // on entry r is q's matrix already
    double ox, oy, oz;
    bool newton;
    rotation_step(a, r, ox, oy, oz, newton);
    const double w = std::sqrt(ox * ox + oy * oy + oz * oz);
    if (!(w > tolerance_rad)) {
      converged = true;  // r is the matrix of q
      break;
    }
    double dw, dx, dy, dz;
    if (w < 0.05) {
      // small increment: first-order quaternion (no trigonometry), then normalised
      dw = 1.0;
      dx = 0.5 * ox;
      dy = 0.5 * oy;
      dz = 0.5 * oz;
    } else {
      // a large one (a cold start): the exact rotation, at most a quarter turn at a time
      const double ang = std::min(w, 0.5 * M_PI);
      const double sh = std::sin(0.5 * ang) / w;
      dw = std::cos(0.5 * ang);
      dx = sh * ox;
      dy = sh * oy;
      dz = sh * oz;
    }
    // q <- dq * q (Hamilton product), normalised
    const double nw = dw * qw - dx * qx - dy * qy - dz * qz;
    const double nqx = dw * qx + dx * qw + dy * qz - dz * qy;
    const double nqy = dw * qy - dx * qz + dy * qw + dz * qx;
    const double nqz = dw * qz + dx * qy - dy * qx + dz * qw;
    const double inv_norm = 1.0 / std::sqrt(nw * nw + nqx * nqx + nqy * nqy + nqz * nqz);
    qw = nw * inv_norm;
    qx = nqx * inv_norm;
    qy = nqy * inv_norm;
    qz = nqz * inv_norm;
    // a Newton step leaves an error of the order of its square: below the tolerance, no check
    if (newton && w * w <= tolerance_rad) break;
  }
  if (!converged) quaternion_matrix(qw, qx, qy, qz, r);
  q_io = Eigen::Quaterniond(qw, qx, qy, qz);
}

}  // namespace teleop::sim::deformable::detail
