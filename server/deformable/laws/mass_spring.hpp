#pragma once
// Internal: the mass-spring law of server/deformable/ (model mass_spring). Every edge is a spring
// of stiffness k and rest length l0 with a damper beta k along it, and every node is tied to the
// centre node by a radial spring of its own stiffness and damper. The tension of one spring
// (positive: it pulls its ends together) is
//   T = k (l - l0) + beta k dl/dt,
// written here once per arithmetic: in double for the general force pass and the scalar kernel
// (spring_tension), in single precision for the simd kernel's portable path (spring_scale), and
// eight at a time for its AVX2 path (spring_scale8). Not part of the deformable API.
#include <algorithm>
#include <cmath>

#include "server/deformable/kernels.hpp"

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace teleop::sim::deformable::detail {

/// out[k] = 1 / sqrt(in[k]) for squared lengths [m^2] (forces.cpp): a loop the compiler
/// vectorises. The 1e-30 is below the rounding of any real length but keeps a zero length finite
/// (1e15 m^-1, multiplied by a zero vector).
void inverse_sqrt(const double* __restrict in, double* __restrict out, int count);

/// The tension of a spring of stiffness k [N/m], rest length l0 [m] and damper beta k [N s/m]
/// from its squared length l2 [m^2], 1 / length inv_l [1/m] and elongation rate [m/s].
TELEOP_ALWAYS_INLINE double spring_tension(double k, double l2, double inv_l, double l0,
                                           double beta, double rate) {
  return k * (l2 * inv_l - l0) + beta * k * rate;
}

/// The same tension per unit length, (k (l - l0) + beta k dl/dt) / l, in single precision for a
/// spring to d = (dx, dy, dz) of relative velocity (ex, ey, ez) (the simd kernel's portable path).
inline float spring_scale(float dx, float dy, float dz, float ex, float ey, float ez, float k,
                          float l0, float beta) {
  const float l2 = dx * dx + dy * dy + dz * dz + 1e-30f;
  const float inv_l = 1.0f / std::sqrt(l2);
  const float rate = (ex * dx + ey * dy + ez * dz) * inv_l;
  return (k * (l2 * inv_l - l0) + beta * k * rate) * inv_l;
}

#if defined(__GNUC__) && defined(__x86_64__)
/// spring_scale for 8 springs at once (the simd kernel's AVX2 path), with 1 / l from the CPU's
/// reciprocal square-root estimate y0 (12 bits) and one Newton step, 1 / l = y0 u with
/// u = 1.5 - 0.5 l2 y0^2: at most 2.0e-7 relative error (1.7 float ulps), against 1e-7 for the
/// exact sqrt and division of spring_scale. The same value as spring_scale, arranged for a short
/// dependency chain after the estimate:
///   (k (l - l0) + beta k rate) / l = (k y0 u) ((l2 + beta (e . d)) y0 u - l0),
/// with l2 + beta (e . d) and 0.5 l2 formed while the estimate is computed and k y0, w y0 beside
/// the Newton factor u (the force pass is bound by these chains, not by its instruction count).
/// The estimate is the CPU's (its table may differ between CPU makers, so may the last bits of a
/// force); on one machine the result is deterministic.
__attribute__((target("avx2,fma"))) inline __m256 spring_scale8(__m256 dx, __m256 dy, __m256 dz,
                                                                __m256 ex, __m256 ey, __m256 ez,
                                                                __m256 k, __m256 l0, __m256 beta) {
  const __m256 l2 = _mm256_add_ps(_mm256_fmadd_ps(dx, dx, _mm256_set1_ps(1e-30f)),
                                  _mm256_fmadd_ps(dz, dz, _mm256_mul_ps(dy, dy)));
  const __m256 y0 = _mm256_rsqrt_ps(l2);  // ~12 bits; one Newton step: ~23 bits
  const __m256 dot = _mm256_fmadd_ps(ez, dz, _mm256_fmadd_ps(ey, dy, _mm256_mul_ps(ex, dx)));
  const __m256 w = _mm256_fmadd_ps(beta, dot, l2);
  const __m256 half_l2 = _mm256_mul_ps(_mm256_set1_ps(0.5f), l2);
  const __m256 u = _mm256_fnmadd_ps(_mm256_mul_ps(half_l2, y0), y0, _mm256_set1_ps(1.5f));
  const __m256 ky = _mm256_mul_ps(k, y0), wy = _mm256_mul_ps(w, y0);
  return _mm256_mul_ps(_mm256_mul_ps(ky, u), _mm256_fmsub_ps(wy, u, l0));
}
#endif

/// Mass-spring edge forces into s.edge_force (the force on each edge's first node), and with
/// flags.jacobian the blocks for the implicit solve (s.edge_dir, s.edge_coef).
TELEOP_ALWAYS_INLINE void mass_spring_edge_forces(const DeformableModel& m, DeformableState& s,
                                                  ForceFlags flags) {
  const int ne = static_cast<int>(m.edges.cols());
  const Eigen::Matrix3Xd& x = s.x;
  const Eigen::Matrix3Xd& v = s.v;
  const double beta = m.params.stiffness_damping_s;
  Eigen::Matrix3Xd& Fe = s.edge_force;
  // 1 / length of every edge first, in a separate pass the compiler vectorises (sqrt and
  // division two at a time, off the critical path of the force loop)
  Eigen::VectorXd& inv_len = s.edge_scratch;
  for (int e = 0; e < ne; ++e) {
    s.edge_length2(e) = (x.col(m.edges(1, e)) - x.col(m.edges(0, e))).squaredNorm();
  }
  inverse_sqrt(s.edge_length2.data(), inv_len.data(), ne);
  if (!flags.jacobian) {
    // the explicit/symplectic hot path in plain scalar arithmetic on the raw 3 x N arrays:
    // Eigen's 2+1-lane handling of 3-vectors (shuffles for every dot product) costs more than
    // it saves here
    const double* xp = x.data();
    const double* vp = v.data();
    const int* ep = m.edges.data();
    const double* kp = m.edge_k_iso.data();
    const double* l0 = m.rest_length_m.data();
    const double* il = inv_len.data();
    double* fp = Fe.data();
    for (int e = 0; e < ne; ++e) {
      const int i = 3 * ep[2 * e], j = 3 * ep[2 * e + 1];
      const double dx = xp[j] - xp[i], dy = xp[j + 1] - xp[i + 1], dz = xp[j + 2] - xp[i + 2];
      const double inv_l = il[e];
      const double ux = dx * inv_l, uy = dy * inv_l, uz = dz * inv_l;
      const double rate =
          (vp[j] - vp[i]) * ux + (vp[j + 1] - vp[i + 1]) * uy + (vp[j + 2] - vp[i + 2]) * uz;
      const double fs =
          spring_tension(kp[e], dx * dx + dy * dy + dz * dz, inv_l, l0[e], beta, rate);
      fp[3 * e] = fs * ux;
      fp[3 * e + 1] = fs * uy;
      fp[3 * e + 2] = fs * uz;
    }
    return;
  }
  for (int e = 0; e < ne; ++e) {
    const int i = m.edges(0, e), j = m.edges(1, e);
    const Eigen::Vector3d d = x.col(j) - x.col(i);
    const double inv_l = inv_len(e);
    const Eigen::Vector3d u = d * inv_l;
    const double k = m.edge_k_iso(e);
    const double fs = spring_tension(k, d.squaredNorm(), inv_l, m.rest_length_m(e), beta,
                                     (v.col(j) - v.col(i)).dot(u));
    Fe.col(e) = fs * u;
    // clamped spring Jacobian: the transverse term only when stretched (keeps it SPD)
    const double kt = k * std::max(0.0, 1.0 - m.rest_length_m(e) * inv_l);
    s.edge_dir.col(e) = u;
    s.edge_coef.col(e) << kt, k - kt, 0.0, beta * k;
  }
}

/// Adds the radial springs between the nodes and the centre node to s.work_f (the reactions to
/// column N), and with flags.jacobian stores their implicit blocks (s.radial_dir, s.radial_coef).
/// Needs m.has_centre.
TELEOP_ALWAYS_INLINE void add_radial_forces(const DeformableModel& m, DeformableState& s,
                                            ForceFlags flags) {
  const int n = m.node_count;
  const DeformableParams& p = m.params;
  Eigen::Matrix3Xd& F = s.work_f;
  const Eigen::Matrix3Xd& x = s.x;
  const Eigen::Matrix3Xd& v = s.v;
  Eigen::Vector3d fc = Eigen::Vector3d::Zero();
  Eigen::VectorXd& inv_len = s.node_scratch;
  for (int i = 0; i < n; ++i) s.node_length2(i) = (x.col(i) - s.centre_x).squaredNorm();
  inverse_sqrt(s.node_length2.data(), inv_len.data(), n);
  if (!flags.jacobian) {
    const double* xp = x.data();
    const double* vp = v.data();
    double* fp = F.data();
    const double cx = s.centre_x.x(), cy = s.centre_x.y(), cz = s.centre_x.z();
    const double cvx = s.centre_v.x(), cvy = s.centre_v.y(), cvz = s.centre_v.z();
    const double* kr = m.radial_k.data();
    const double* r0 = m.radial_rest_m.data();
    const double* il = inv_len.data();
    const double rd = p.radial_damping_s;
    double fcx = 0.0, fcy = 0.0, fcz = 0.0;
    for (int i = 0; i < n; ++i) {
      const int a = 3 * i;
      const double dx = xp[a] - cx, dy = xp[a + 1] - cy, dz = xp[a + 2] - cz;
      const double inv_l = il[i];
      const double ux = dx * inv_l, uy = dy * inv_l, uz = dz * inv_l;
      const double rate = (vp[a] - cvx) * ux + (vp[a + 1] - cvy) * uy + (vp[a + 2] - cvz) * uz;
      const double fs = -spring_tension(kr[i], dx * dx + dy * dy + dz * dz, inv_l, r0[i], rd, rate);
      fp[a] += fs * ux;
      fp[a + 1] += fs * uy;
      fp[a + 2] += fs * uz;
      fcx -= fs * ux;
      fcy -= fs * uy;
      fcz -= fs * uz;
    }
    F.col(n) += Eigen::Vector3d(fcx, fcy, fcz);
    return;
  }
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d d = x.col(i) - s.centre_x;
    const double inv_l = inv_len(i);
    const Eigen::Vector3d u = d * inv_l;
    const double k = m.radial_k(i);
    const double fs = -spring_tension(k, d.squaredNorm(), inv_l, m.radial_rest_m(i),
                                      p.radial_damping_s, (v.col(i) - s.centre_v).dot(u));
    F.col(i) += fs * u;
    fc -= fs * u;
    const double kt = k * std::max(0.0, 1.0 - m.radial_rest_m(i) * inv_l);
    s.radial_dir.col(i) = u;
    s.radial_coef.col(i) << kt, k - kt, 0.0, p.radial_damping_s * k;
  }
  F.col(n) += fc;
}

}  // namespace teleop::sim::deformable::detail
