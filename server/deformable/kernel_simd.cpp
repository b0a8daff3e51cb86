// Kernel simd of the mass-spring symplectic-Euler step (params.kernel == kSimd): the law of
// laws/mass_spring.hpp, the plane contact of plane_contact.hpp and the node update of the scalar
// kernel (kernel_scalar.cpp) in another data layout.
//
// The scalar kernel visits each edge once and scatters its reaction, which keeps it scalar.
// Here every node gathers its own edges instead (each edge is
// evaluated twice, once from each end, with exactly opposite results: d_ji = -d_ij bit for bit),
// so neighbouring nodes are independent and 8 of them are computed at once:
//   1. pack: per node 8 floats (position relative to the centre node, 0, velocity relative to its
//      velocity, 0), so a node is one 32-byte load (the AoS double state stays the state); with
//      AVX2 a node's x and v are one 4-double load each, converted and stored as one vector
//      (within a sub-stepped step the previous sub-step's position pass has already done it);
//   2. internal forces in float: per block of 8 nodes, their packs and, per neighbour slot (the
//      ELL table of the model, slot-major, padded with the node itself at k = 0), their
//      neighbours' packs, each 8 x 8 block transposed in registers (AVX2; cheaper than gather
//      instructions here), radial springs and edges; the centre node's reaction summed in double;
//   3. integration in double per node: gravity, drag, f_ext, plane contact (springs, then the
//      damping/friction impulses), held nodes, the post-step sums: as in the scalar kernel.
// Without AVX2 and FMA (checked once at run time) a portable loop does the same operations (but
// 1 / length by an exact square root and division, not the AVX2 path's estimate + Newton step).
// Single precision in the forces: positions relative to the centre (|x| < ~1 m) carry 6e-8 m of
// rounding, a spring force error of k * 6e-8 m (1e-5 N at k = 150 N/m); the test
// SimdKernel.MatchesTheScalarKernel bounds the difference to the scalar kernel.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "server/deformable/integrators.hpp"
#include "server/deformable/kernels.hpp"
#include "server/deformable/laws/mass_spring.hpp"
#include "server/deformable/plane_contact.hpp"

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && \
    !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
#define TELEOP_SIMD_CLONES \
  __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define TELEOP_SIMD_CLONES
#endif

namespace teleop::sim::deformable::detail {

namespace {

// The body's internal forces (edges and radial springs) into s.force (AoS double); returns the
// radial springs' reaction on the centre node. Padding nodes have k = 0 everywhere.
struct Internal {
  double centre[3] = {0.0, 0.0, 0.0};
};

// Packs node i: (x - c, y - c, z - c, 0, vx - cv, vy - cv, vz - cv, 0) as floats.
inline void pack_node(const double* x, const double* v, const double* c, const double* cv,
                      float* out) {
  out[0] = static_cast<float>(x[0] - c[0]);
  out[1] = static_cast<float>(x[1] - c[1]);
  out[2] = static_cast<float>(x[2] - c[2]);
  out[3] = 0.0f;
  out[4] = static_cast<float>(v[0] - cv[0]);
  out[5] = static_cast<float>(v[1] - cv[1]);
  out[6] = static_cast<float>(v[2] - cv[2]);
  out[7] = 0.0f;
}

// Portable path (no AVX2): the same arithmetic one node at a time.
Internal internal_forces_portable(const DeformableModel& m, DeformableState& s) {
  const int n = m.node_count, stride = m.simd_stride, width = m.simd_width;
  const float* pk = s.simd_pack.data();
  const float beta = static_cast<float>(m.params.stiffness_damping_s);
  const float rd = static_cast<float>(m.params.radial_damping_s);
  double* f = s.force.data();
  Internal out;
  for (int i = 0; i < n; ++i) {
    const float* a = pk + 8 * i;
    // radial spring: the centre is at the origin of the packed frame, at rest in it
    const float sr = -spring_scale(a[0], a[1], a[2], a[4], a[5], a[6],
                                   m.simd_radial_k[static_cast<std::size_t>(i)],
                                   m.simd_radial_rest[static_cast<std::size_t>(i)], rd);
    float fx = sr * a[0], fy = sr * a[1], fz = sr * a[2];
    out.centre[0] -= static_cast<double>(fx);
    out.centre[1] -= static_cast<double>(fy);
    out.centre[2] -= static_cast<double>(fz);
    for (int slot = 0; slot < width; ++slot) {
      const std::size_t o = static_cast<std::size_t>(slot) * static_cast<std::size_t>(stride) +
                            static_cast<std::size_t>(i);
      const float* b = pk + m.simd_neighbour[o];
      const float dx = b[0] - a[0], dy = b[1] - a[1], dz = b[2] - a[2];
      const float se = spring_scale(dx, dy, dz, b[4] - a[4], b[5] - a[5], b[6] - a[6], m.simd_k[o],
                                    m.simd_rest[o], beta);
      fx += se * dx;
      fy += se * dy;
      fz += se * dz;
    }
    f[3 * i] = static_cast<double>(fx);
    f[3 * i + 1] = static_cast<double>(fy);
    f[3 * i + 2] = static_cast<double>(fz);
  }
  return out;
}

#if defined(__GNUC__) && defined(__x86_64__)
#define TELEOP_HAVE_AVX2_PATH 1

// Rows r[0..7] (8 floats each) to columns: afterwards r[c][l] is the old r[l][c].
__attribute__((target("avx2,fma"))) inline void transpose8(__m256* r) {
  const __m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpackhi_ps(r[0], r[1]);
  const __m256 t2 = _mm256_unpacklo_ps(r[2], r[3]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
  const __m256 t4 = _mm256_unpacklo_ps(r[4], r[5]), t5 = _mm256_unpackhi_ps(r[4], r[5]);
  const __m256 t6 = _mm256_unpacklo_ps(r[6], r[7]), t7 = _mm256_unpackhi_ps(r[6], r[7]);
  const __m256 s0 = _mm256_shuffle_ps(t0, t2, 0x44), s1 = _mm256_shuffle_ps(t0, t2, 0xEE);
  const __m256 s2 = _mm256_shuffle_ps(t1, t3, 0x44), s3 = _mm256_shuffle_ps(t1, t3, 0xEE);
  const __m256 s4 = _mm256_shuffle_ps(t4, t6, 0x44), s5 = _mm256_shuffle_ps(t4, t6, 0xEE);
  const __m256 s6 = _mm256_shuffle_ps(t5, t7, 0x44), s7 = _mm256_shuffle_ps(t5, t7, 0xEE);
  r[0] = _mm256_permute2f128_ps(s0, s4, 0x20);
  r[1] = _mm256_permute2f128_ps(s1, s5, 0x20);
  r[2] = _mm256_permute2f128_ps(s2, s6, 0x20);
  r[3] = _mm256_permute2f128_ps(s3, s7, 0x20);
  r[4] = _mm256_permute2f128_ps(s0, s4, 0x31);
  r[5] = _mm256_permute2f128_ps(s1, s5, 0x31);
  r[6] = _mm256_permute2f128_ps(s2, s6, 0x31);
  r[7] = _mm256_permute2f128_ps(s3, s7, 0x31);
}

// Four nodes' (X, Y, Z) to x0 y0 z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3 in o[0..2].
__attribute__((target("avx2,fma"))) inline void aos(__m256d X, __m256d Y, __m256d Z, __m256d* o) {
  const __m256d a = _mm256_unpacklo_pd(X, Y);  // x0 y0 x2 y2
  const __m256d b = _mm256_unpackhi_pd(X, Y);  // x1 y1 x3 y3
  const __m256d d = _mm256_unpacklo_pd(Z, b);  // z0 x1 z2 x3
  const __m256d e = _mm256_unpackhi_pd(b, Z);  // y1 z1 y3 z3
  o[0] = _mm256_permute2f128_pd(a, d, 0x20);
  o[1] = _mm256_permute2f128_pd(e, a, 0x30);
  o[2] = _mm256_permute2f128_pd(d, e, 0x31);
}

// Step 3b's arithmetic on the 3N coordinates (blocks of 12 = 4 nodes, three vectors carrying the
// x/y/z pattern): f = f_int + f_ext + m (g + alpha v_mean - alpha v), then v += h f / m.
struct FlatUpdate {
  __m256d g[3];
  __m256d alpha, h;
  const double* fext;
  const double* dm;
  const double* dim;
  double* v;
  double* f;
};

__attribute__((target("avx2,fma"))) inline FlatUpdate flat_update(const DeformableModel& m,
                                                                  DeformableState& s, double h,
                                                                  const double* gp) {
  FlatUpdate u;
  u.g[0] = _mm256_setr_pd(gp[0], gp[1], gp[2], gp[0]);
  u.g[1] = _mm256_setr_pd(gp[1], gp[2], gp[0], gp[1]);
  u.g[2] = _mm256_setr_pd(gp[2], gp[0], gp[1], gp[2]);
  u.alpha = _mm256_set1_pd(m.params.mass_damping_per_s);
  u.h = _mm256_set1_pd(h);
  u.fext = s.f_ext.data();
  u.dm = m.simd_dof_mass.data();
  u.dim = m.simd_dof_inv_mass.data();
  u.v = s.v.data();
  u.f = s.force.data();
  return u;
}

// AVX2 path: 8 nodes at a time; each node's 8 packed floats (and each neighbour's) are one
// 32-byte load, the 8 x 8 block transposed to coordinates in registers (cheaper here than
// gather instructions).
__attribute__((target("avx2,fma"))) Internal internal_forces_avx2(const DeformableModel& m,
                                                                  DeformableState& s) {
  const int n = m.node_count, stride = m.simd_stride, width = m.simd_width;
  const float* pk = s.simd_pack.data();
  const __m256 beta = _mm256_set1_ps(static_cast<float>(m.params.stiffness_damping_s));
  const __m256 rd = _mm256_set1_ps(static_cast<float>(m.params.radial_damping_s));
  const int* nb = m.simd_neighbour.data();
  const float* kk = m.simd_k.data();
  const float* ll = m.simd_rest.data();
  double* f = s.force.data();
  __m256d cx = _mm256_setzero_pd(), cy = cx, cz = cx;  // centre reaction, 4 partial sums each
  alignas(32) float out[3][8];
  for (int i = 0; i < stride; i += 8) {
    __m256 a[8];
    for (int l = 0; l < 8; ++l) a[l] = _mm256_loadu_ps(pk + 8 * (i + l));
    transpose8(a);
    const __m256 zero = _mm256_setzero_ps();
    const __m256 sr = _mm256_sub_ps(
        zero, spring_scale8(a[0], a[1], a[2], a[4], a[5], a[6],
                            _mm256_loadu_ps(&m.simd_radial_k[static_cast<std::size_t>(i)]),
                            _mm256_loadu_ps(&m.simd_radial_rest[static_cast<std::size_t>(i)]), rd));
    __m256 fx = _mm256_mul_ps(sr, a[0]), fy = _mm256_mul_ps(sr, a[1]), fz = _mm256_mul_ps(sr, a[2]);
    cx = _mm256_sub_pd(cx, _mm256_add_pd(_mm256_cvtps_pd(_mm256_castps256_ps128(fx)),
                                         _mm256_cvtps_pd(_mm256_extractf128_ps(fx, 1))));
    cy = _mm256_sub_pd(cy, _mm256_add_pd(_mm256_cvtps_pd(_mm256_castps256_ps128(fy)),
                                         _mm256_cvtps_pd(_mm256_extractf128_ps(fy, 1))));
    cz = _mm256_sub_pd(cz, _mm256_add_pd(_mm256_cvtps_pd(_mm256_castps256_ps128(fz)),
                                         _mm256_cvtps_pd(_mm256_extractf128_ps(fz, 1))));
    for (int slot = 0; slot < width; ++slot) {
      const int o = slot * stride + i;
      __m256 b[8];
      for (int l = 0; l < 8; ++l) b[l] = _mm256_loadu_ps(pk + nb[o + l]);
      transpose8(b);
      const __m256 dx = _mm256_sub_ps(b[0], a[0]), dy = _mm256_sub_ps(b[1], a[1]),
                   dz = _mm256_sub_ps(b[2], a[2]);
      const __m256 se = spring_scale8(dx, dy, dz, _mm256_sub_ps(b[4], a[4]),
                                      _mm256_sub_ps(b[5], a[5]), _mm256_sub_ps(b[6], a[6]),
                                      _mm256_loadu_ps(kk + o), _mm256_loadu_ps(ll + o), beta);
      fx = _mm256_fmadd_ps(se, dx, fx);
      fy = _mm256_fmadd_ps(se, dy, fy);
      fz = _mm256_fmadd_ps(se, dz, fz);
    }
    if (i + 8 <= n) {  // 8 nodes' forces to 24 doubles, x y z per node, in registers
      __m256d lo[3], hi[3];
      aos(_mm256_cvtps_pd(_mm256_castps256_ps128(fx)), _mm256_cvtps_pd(_mm256_castps256_ps128(fy)),
          _mm256_cvtps_pd(_mm256_castps256_ps128(fz)), lo);
      aos(_mm256_cvtps_pd(_mm256_extractf128_ps(fx, 1)),
          _mm256_cvtps_pd(_mm256_extractf128_ps(fy, 1)),
          _mm256_cvtps_pd(_mm256_extractf128_ps(fz, 1)), hi);
      for (int t = 0; t < 3; ++t) {
        _mm256_storeu_pd(f + 3 * i + 4 * t, lo[t]);
        _mm256_storeu_pd(f + 3 * i + 12 + 4 * t, hi[t]);
      }
      continue;
    }
    _mm256_store_ps(out[0], fx);
    _mm256_store_ps(out[1], fy);
    _mm256_store_ps(out[2], fz);
    const int lanes = n - i;
    for (int l = 0; l < lanes; ++l) {
      f[3 * (i + l)] = static_cast<double>(out[0][l]);
      f[3 * (i + l) + 1] = static_cast<double>(out[1][l]);
      f[3 * (i + l) + 2] = static_cast<double>(out[2][l]);
    }
  }
  alignas(32) double sum[3][4];
  _mm256_store_pd(sum[0], cx);
  _mm256_store_pd(sum[1], cy);
  _mm256_store_pd(sum[2], cz);
  Internal r;
  for (int c = 0; c < 3; ++c) r.centre[c] = (sum[c][0] + sum[c][1]) + (sum[c][2] + sum[c][3]);
  return r;
}

// The mass-weighted velocity sum over 12-coordinate blocks (4 nodes, three vectors carrying the
// x/y/z pattern), reduced in a fixed order: pack_all_avx2 and the fused pack of
// flat_positions_sums sum in exactly this order, so they give the same bits.
__attribute__((target("avx2,fma"), always_inline)) inline void momentum_block(const double* dm,
                                                                              const __m256d* vq,
                                                                              __m256d* acc) {
  for (int t = 0; t < 3; ++t) acc[t] = _mm256_fmadd_pd(_mm256_loadu_pd(dm + 4 * t), vq[t], acc[t]);
}

__attribute__((target("avx2,fma"), always_inline)) inline void momentum_reduce(const __m256d* acc,
                                                                               double* out) {
  alignas(32) double lane[3][4];
  for (int t = 0; t < 3; ++t) _mm256_store_pd(lane[t], acc[t]);
  out[0] = out[1] = out[2] = 0.0;
  for (int j = 0; j < 12; ++j) out[j % 3] += lane[j / 4][j % 4];  // coordinate j: component j % 3
}

// Node i's pack from its x and v (the last node's by a masked load: nothing is read past the
// state): a double subtraction rounded to float, as pack_node does, so the two give the same bits.
__attribute__((target("avx2,fma"), always_inline)) inline void pack_one_avx2(
    const double* x, const double* v, int i, int n, __m256d c4, __m256d cv4, float* pk) {
  const __m256i first3 = _mm256_setr_epi64x(-1, -1, -1, 0);
  __m256d xi, vi;
  if (i + 1 < n) {
    xi = _mm256_loadu_pd(x + 3 * i);
    vi = _mm256_loadu_pd(v + 3 * i);
  } else {
    xi = _mm256_maskload_pd(x + 3 * i, first3);
    vi = _mm256_maskload_pd(v + 3 * i, first3);
  }
  const __m128 px = _mm256_cvtpd_ps(_mm256_sub_pd(xi, c4));
  const __m128 pv = _mm256_cvtpd_ps(_mm256_sub_pd(vi, cv4));
  // lanes 3 and 7 (the next node's x and v, or zero) set to zero
  _mm256_storeu_ps(pk + 8 * i, _mm256_blend_ps(_mm256_set_m128(pv, px), _mm256_setzero_ps(), 0x88));
}

// Step 1 with AVX2: the pack of every node (one 4-double load of x and of v per node) and the
// mass-weighted velocity sum (momentum_block over whole blocks of 4 nodes, then the remaining
// nodes in order).
__attribute__((target("avx2,fma"))) void pack_all_avx2(const DeformableModel& m, DeformableState& s,
                                                       const double* c, const double* cv,
                                                       double* vm) {
  const int n = m.node_count;
  const double* x = s.x.data();
  const double* v = s.v.data();
  const double* dm = m.simd_dof_mass.data();
  float* pk = s.simd_pack.data();
  const __m256d c4 = _mm256_setr_pd(c[0], c[1], c[2], 0.0);
  const __m256d cv4 = _mm256_setr_pd(cv[0], cv[1], cv[2], 0.0);
  __m256d acc[3] = {_mm256_setzero_pd(), _mm256_setzero_pd(), _mm256_setzero_pd()};
  int i = 0;
  for (; i + 4 <= n; i += 4) {
    const __m256d vq[3] = {_mm256_loadu_pd(v + 3 * i), _mm256_loadu_pd(v + 3 * i + 4),
                           _mm256_loadu_pd(v + 3 * i + 8)};
    momentum_block(dm + 3 * i, vq, acc);
    for (int l = 0; l < 4; ++l) pack_one_avx2(x, v, i + l, n, c4, cv4, pk);
  }
  momentum_reduce(acc, vm);
  for (; i < n; ++i) {
    pack_one_avx2(x, v, i, n, c4, cv4, pk);
    for (int d = 0; d < 3; ++d) vm[d] = std::fma(dm[3 * i + d], v[3 * i + d], vm[d]);
  }
}

// Chosen once: the AVX2 path where the CPU has AVX2 and FMA.
bool use_avx2() { return simd_kernel_vectorised(); }
#endif

// Step 3: per node, in double: the rest of the force, symplectic Euler, contact, held nodes.
TELEOP_SIMD_CLONES
void integrate_nodes(const DeformableModel& m, DeformableState& s, double h, double vmx, double vmy,
                     double vmz, KernelSums& sums) {
  const int n = m.node_count;
  const DeformableParams& p = m.params;
  double* __restrict x = s.x.data();
  double* __restrict v = s.v.data();
  double* __restrict f = s.force.data();  // in: the internal forces; out: the total
  const double* __restrict mp = m.mass_kg.data();
  const double* __restrict imp = m.inv_mass.data();
  const double* __restrict fext = s.f_ext.data();
  const double* __restrict tgt = s.pin_target.data();
  const std::uint8_t* __restrict pin = s.pinned.data();
  const double gx = p.gravity_mps2.x(), gy = p.gravity_mps2.y(), gz = p.gravity_mps2.z();
  const double alpha = p.mass_damping_per_s;
  const bool any_pinned = s.pinned_count > 0;
  double spring_of[8] = {};
  int nc = 0;
  Eigen::Vector3d plane_force = Eigen::Vector3d::Zero();
  NodeSums node_sums;
  for (int i = 0; i < n; ++i) {
    const int a = 3 * i;
    const double mi = mp[i];
    const double xx = x[a], xy = x[a + 1], xz = x[a + 2];
    double vx = v[a], vy = v[a + 1], vz = v[a + 2];
    double ax = f[a] + mi * (gx - alpha * (vx - vmx)) + fext[a];
    double ay = f[a + 1] + mi * (gy - alpha * (vy - vmy)) + fext[a + 1];
    double az = f[a + 2] + mi * (gz - alpha * (vz - vmz)) + fext[a + 2];
    const unsigned touched = node_plane_springs(m, i, xx, xy, xz, spring_of, ax, ay, az, nc);
    f[a] = ax;
    f[a + 1] = ay;
    f[a + 2] = az;
    symplectic_node(m, i, h, mi, imp[i], any_pinned && pin[i] != 0, tgt + a, xx, xy, xz, vx, vy, vz,
                    ax, ay, az, touched, spring_of, x, v, plane_force, node_sums);
  }
  s.contact_count = nc;
  s.plane_force_n = plane_force;
  node_sums.store(sums);
}

#ifdef TELEOP_HAVE_AVX2_PATH
// The helpers of integrate_flat_avx2, always inlined into it (the same instruction set).
#define TELEOP_AVX2_INLINE inline __attribute__((target("avx2,fma"), always_inline))

// Flat step 3a: the plane contacts at the old positions into s.contact_node and
// s.contact_coef (row 0: plane index, row 2: spring force [N]); returns their count.
TELEOP_AVX2_INLINE int flat_contacts(const DeformableModel& m, DeformableState& s) {
  const int n = m.node_count;
  const double* x = s.x.data();
  int nc = 0;
  const int planes = m.plane_count;
  for (int i = 0; i < n && planes > 0; ++i) {
    for (int k = 0; k < planes; ++k) {
      const Plane& pl = m.planes[static_cast<std::size_t>(k)];
      const double dist = pl.normal.x() * x[3 * i] + pl.normal.y() * x[3 * i + 1] +
                          pl.normal.z() * x[3 * i + 2] - pl.offset_m;
      if (dist >= 0.0) continue;
      s.contact_node[static_cast<std::size_t>(nc)] = i;
      s.contact_coef(0, nc) = static_cast<double>(k);
      s.contact_coef(2, nc) = -m.contact_k(i) * dist;  // spring force
      ++nc;
    }
  }
  return nc;
}

// Flat step 3b (see FlatUpdate): blocks of 12 coordinates, then the rest one at a time. Without
// loads (`loads_zero`) f_ext is not read.
TELEOP_AVX2_INLINE void flat_forces_velocities(const DeformableModel& m, DeformableState& s,
                                               double h, const double* gp, bool loads_zero) {
  const int n3 = 3 * m.node_count;
  const FlatUpdate u = flat_update(m, s, h, gp);
  const int blocks = n3 / 12 * 12;
  for (int q0 = 0; q0 < blocks; q0 += 12) {
    for (int t = 0; t < 3; ++t) {
      const int q = q0 + 4 * t;
      const __m256d vq = _mm256_loadu_pd(u.v + q);
      __m256d ft = _mm256_loadu_pd(u.f + q);
      if (!loads_zero) ft = _mm256_add_pd(ft, _mm256_loadu_pd(u.fext + q));
      ft = _mm256_add_pd(
          ft, _mm256_mul_pd(_mm256_loadu_pd(u.dm + q), _mm256_fnmadd_pd(u.alpha, vq, u.g[t])));
      _mm256_storeu_pd(u.f + q, ft);
      _mm256_storeu_pd(u.v + q,
                       _mm256_fmadd_pd(_mm256_mul_pd(u.h, _mm256_loadu_pd(u.dim + q)), ft, vq));
    }
  }
  const double alpha = m.params.mass_damping_per_s;
  for (int q = blocks; q < n3; ++q) {
    const double ft = u.f[q] + u.fext[q] + u.dm[q] * (gp[q % 3] - alpha * u.v[q]);
    u.f[q] = ft;
    u.v[q] += h * u.dim[q] * ft;
  }
}

// Flat step 3c: the nc contacts found by flat_contacts, every spring first (a node may touch two
// planes), then the impulses in order; sets s.contact_count and s.plane_force_n.
TELEOP_AVX2_INLINE void flat_contact_impulses(const DeformableModel& m, DeformableState& s,
                                              double h, int nc) {
  double* v = s.v.data();
  double* f = s.force.data();
  Eigen::Vector3d plane_force = Eigen::Vector3d::Zero();
  for (int c = 0; c < nc; ++c) {
    const int i = s.contact_node[static_cast<std::size_t>(c)];
    const Plane& pl = m.planes[static_cast<std::size_t>(s.contact_coef(0, c))];
    const double spring = s.contact_coef(2, c);
    const double hm = h * m.inv_mass(i);
    for (int d = 0; d < 3; ++d) {
      f[3 * i + d] += spring * pl.normal(d);
      v[3 * i + d] += hm * spring * pl.normal(d);
    }
  }
  for (int c = 0; c < nc; ++c) {
    const int i = s.contact_node[static_cast<std::size_t>(c)];
    const Plane& pl = m.planes[static_cast<std::size_t>(s.contact_coef(0, c))];
    contact_impulse(pl.normal, m.mass_kg(i), m.contact_c(i), h * s.contact_coef(2, c),
                    m.params.friction ? pl.friction : 0.0, h, v[3 * i], v[3 * i + 1], v[3 * i + 2],
                    plane_force);
  }
  s.contact_count = nc;
  s.plane_force_n = plane_force;
}

// Flat step 3d: x += h v and the post-step sums, in per-lane partial sums over blocks of 12
// coordinates (a fixed order: deterministic), then the remaining nodes one at a time.
// With `next` (not null) it also packs the nodes' new x and v for the next sub-step, relative to
// the centre node's new position and velocity next->c, next->cv (as pack_all_avx2 would, the
// same bits), and sums their momentum into next->vm in momentum_block's order.
struct NextPack {
  double c[3], cv[3];
  double vm[3];
};

// Four nodes' (x, y, z) rounded to float, f = x0 y0 z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3, to
// node[l] = (x_l, y_l, z_l, 0).
TELEOP_AVX2_INLINE void split_block(const __m128* f, __m128* node) {
  const __m128 zero = _mm_setzero_ps();
  const __m128i a = _mm_castps_si128(f[0]), b = _mm_castps_si128(f[1]), c = _mm_castps_si128(f[2]);
  node[0] = _mm_blend_ps(f[0], zero, 8);
  node[1] = _mm_blend_ps(_mm_castsi128_ps(_mm_alignr_epi8(b, a, 12)), zero, 8);
  node[2] = _mm_blend_ps(_mm_castsi128_ps(_mm_alignr_epi8(c, b, 8)), zero, 8);
  node[3] = _mm_castsi128_ps(_mm_srli_si128(c, 4));
}

// Four nodes' packs from the three vectors of their new x (xq) and v (vq), coordinates x0 y0 z0
// x1 | y1 z1 x2 y2 | z2 x3 y3 z3: each rounded to float and split into 4 x (x, y, z, 0).
TELEOP_AVX2_INLINE void pack_block(const __m256d* xq, const __m256d* vq, const __m256d* cpat,
                                   const __m256d* cvpat, float* pk) {
  __m128 xf[3], vf[3];
  for (int t = 0; t < 3; ++t) {
    xf[t] = _mm256_cvtpd_ps(_mm256_sub_pd(xq[t], cpat[t]));
    vf[t] = _mm256_cvtpd_ps(_mm256_sub_pd(vq[t], cvpat[t]));
  }
  __m128 nx[4], nv[4];
  split_block(xf, nx);
  split_block(vf, nv);
  for (int l = 0; l < 4; ++l) _mm256_storeu_ps(pk + 8 * l, _mm256_set_m128(nv[l], nx[l]));
}

// The x/y/z pattern of a block of 12 coordinates (x0 y0 z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3) for
// the vector (c0, c1, c2).
TELEOP_AVX2_INLINE void block_pattern(const double* c, __m256d* pat) {
  pat[0] = _mm256_setr_pd(c[0], c[1], c[2], c[0]);
  pat[1] = _mm256_setr_pd(c[1], c[2], c[0], c[1]);
  pat[2] = _mm256_setr_pd(c[2], c[0], c[1], c[2]);
}

// The 4 nodes' squared speeds (x^2 + y^2) + z^2 of a block from the squares of its 12
// coordinates: a = x^2 of nodes 0-3, b = y^2, c = z^2 gathered from a0 a1 a2 a3 | b0 b1 b2 b3 |
// c0 c1 c2 c3.
TELEOP_AVX2_INLINE __m256d block_speeds2(const __m256d* v2s) {
  const __m256d sa = _mm256_permute4x64_pd(
      _mm256_blend_pd(_mm256_blend_pd(v2s[0], v2s[1], 0x4), v2s[2], 0x2), 0x6C);  // 0 3 2 1
  const __m256d sb = _mm256_permute4x64_pd(
      _mm256_blend_pd(_mm256_blend_pd(v2s[1], v2s[0], 0x2), v2s[2], 0x4), 0xB1);  // 1 0 3 2
  const __m256d sc = _mm256_permute4x64_pd(
      _mm256_blend_pd(_mm256_blend_pd(v2s[2], v2s[0], 0x4), v2s[1], 0x2), 0xC6);  // 2 1 0 3
  return _mm256_add_pd(_mm256_add_pd(sa, sb), sc);
}

// The per-lane partial sums of the blocks (ax: positions, av: squared speeds, am: mass-weighted
// positions) and the lanes' largest squared speed, reduced in a fixed order into sums.
TELEOP_AVX2_INLINE void reduce_block_sums(const __m256d* ax, const __m256d* av, const __m256d* am,
                                          __m256d top, KernelSums& sums) {
  alignas(32) double lane[3][3][4];
  for (int t = 0; t < 3; ++t) {
    _mm256_store_pd(lane[0][t], ax[t]);
    _mm256_store_pd(lane[1][t], av[t]);
    _mm256_store_pd(lane[2][t], am[t]);
  }
  alignas(32) double tops[4];
  _mm256_store_pd(tops, top);
  sums.fastest2 = std::max(std::max(tops[0], tops[1]), std::max(tops[2], tops[3]));
  sums.sum_x = 0.0;
  sums.sum_v = 0.0;
  sums.mx[0] = sums.mx[1] = sums.mx[2] = 0.0;
  for (int j = 0; j < 12; ++j) {  // coordinate j of the block is component j % 3
    sums.sum_x += lane[0][j / 4][j % 4];
    sums.sum_v += lane[1][j / 4][j % 4];
    sums.mx[j % 3] += lane[2][j / 4][j % 4];
  }
}

// x += h v for the nodes from `first` on (those past the last whole block), one by one, added to
// the sums (and the momentum and packs with kPack).
template <bool kPack>
TELEOP_AVX2_INLINE void tail_positions_sums(const DeformableModel& m, DeformableState& s, double h,
                                            int first, KernelSums& sums, NextPack* next) {
  double* x = s.x.data();
  const double* v = s.v.data();
  const double* dm = m.simd_dof_mass.data();
  float* pk = s.simd_pack.data();
  for (int i = first; i < m.node_count; ++i) {
    double sp2 = 0.0;
    for (int d = 0; d < 3; ++d) {
      const int q = 3 * i + d;
      const double xq = x[q] + h * v[q];
      x[q] = xq;
      sp2 += v[q] * v[q];
      sums.sum_x += xq;
      sums.mx[d] += dm[q] * xq;
      if (kPack) next->vm[d] = std::fma(dm[q], v[q], next->vm[d]);
    }
    if (kPack) pack_node(x + 3 * i, v + 3 * i, next->c, next->cv, pk + 8 * i);
    sums.sum_v += sp2;
    sums.fastest2 = sp2 > sums.fastest2 ? sp2 : sums.fastest2;
  }
}

template <bool kPack>
TELEOP_AVX2_INLINE void flat_positions_sums(const DeformableModel& m, DeformableState& s, double h,
                                            KernelSums& sums, NextPack* next) {
  const int n3 = 3 * m.node_count;
  double* x = s.x.data();
  const double* v = s.v.data();
  const double* dm = m.simd_dof_mass.data();
  float* pk = s.simd_pack.data();
  const __m256d vh = _mm256_set1_pd(h);
  const int blocks = n3 / 12 * 12;
  __m256d ax[3], av[3], am[3], acc[3], cpat[3], cvpat[3];
  for (int t = 0; t < 3; ++t) ax[t] = av[t] = am[t] = acc[t] = _mm256_setzero_pd();
  if (kPack) {
    block_pattern(next->c, cpat);
    block_pattern(next->cv, cvpat);
  }
  __m256d top = _mm256_setzero_pd();  // lane l: the largest squared speed of node l of a block
  for (int q0 = 0; q0 < blocks; q0 += 12) {
    __m256d xs[3], vs[3], v2s[3];
    for (int t = 0; t < 3; ++t) {
      const int q = q0 + 4 * t;
      const __m256d vq = _mm256_loadu_pd(v + q);
      const __m256d xq = _mm256_fmadd_pd(vh, vq, _mm256_loadu_pd(x + q));
      _mm256_storeu_pd(x + q, xq);
      const __m256d v2 = _mm256_mul_pd(vq, vq);
      ax[t] = _mm256_add_pd(ax[t], xq);
      av[t] = _mm256_add_pd(av[t], v2);
      am[t] = _mm256_fmadd_pd(_mm256_loadu_pd(dm + q), xq, am[t]);
      xs[t] = xq;
      vs[t] = vq;
      v2s[t] = v2;
    }
    top = _mm256_max_pd(block_speeds2(v2s), top);  // sp2 > top ? sp2 : top
    if (kPack) {
      momentum_block(dm + q0, vs, acc);
      pack_block(xs, vs, cpat, cvpat, pk + 8 * (q0 / 3));
    }
  }
  reduce_block_sums(ax, av, am, top, sums);
  if (kPack) momentum_reduce(acc, next->vm);
  tail_positions_sums<kPack>(m, s, h, blocks / 3, sums, next);
  if (!(sums.sum_v == sums.sum_v)) sums.fastest2 = sums.sum_v;  // a NaN fails every comparison
}

// Step 3 when no node is held (the usual case), in flat AVX2 passes over the 3N coordinates
// (blocks of 12 coordinates = 4 nodes = 3 vectors carry the x/y/z pattern):
//   contacts at the old positions into a list; f = f_int + f_ext + m (g + alpha v_mean - alpha v)
//   and v += h f / m; the contact springs, then the contact impulses; x += h v with the sums in
//   per-lane partial sums (a fixed order: deterministic).
// The same physics as integrate_nodes (the rounding differs: the m g' - alpha m v form).
// (Separate passes: one pass doing all of it per block of 12 is slower.)
__attribute__((target("avx2,fma"))) void integrate_flat_avx2(const DeformableModel& m,
                                                             DeformableState& s, double h,
                                                             const double* gp, bool loads_zero,
                                                             KernelSums& sums, NextPack* next) {
  const int nc = flat_contacts(m, s);  // at the old positions
  flat_forces_velocities(m, s, h, gp, loads_zero);
  flat_contact_impulses(m, s, h, nc);
  if (next != nullptr) {
    flat_positions_sums<true>(m, s, h, sums, next);
  } else {
    flat_positions_sums<false>(m, s, h, sums, nullptr);
  }
}

#undef TELEOP_AVX2_INLINE
#endif

}  // namespace

void step_mass_spring_simd(const DeformableModel& m, DeformableState& s, double h, bool loads_zero,
                           bool pack_next, KernelSums& sums) {
  const int n = m.node_count;
  const DeformableParams& p = m.params;
  const double c[3] = {s.centre_x.x(), s.centre_x.y(), s.centre_x.z()};
  const double cv[3] = {s.centre_v.x(), s.centre_v.y(), s.centre_v.z()};

  // pack, and the mass-weighted velocity sum for the drag (relative to the mean velocity: damps
  // deformation, keeps momentum); both already done by the previous sub-step if it says so
  const double* x = s.x.data();
  const double* v = s.v.data();
  const double* mp = m.mass_kg.data();
  float* pk = s.simd_pack.data();
  double vm[3] = {0.0, 0.0, 0.0};
  const bool fresh = s.simd_pack_fresh;
  s.simd_pack_fresh = false;
  if (fresh) {
    vm[0] = s.simd_vm[0];
    vm[1] = s.simd_vm[1];
    vm[2] = s.simd_vm[2];
  } else {
#ifdef TELEOP_HAVE_AVX2_PATH
    if (use_avx2()) {
      pack_all_avx2(m, s, c, cv, vm);
    } else {
#endif
      for (int i = 0; i < n; ++i) {
        pack_node(x + 3 * i, v + 3 * i, c, cv, pk + 8 * i);
        vm[0] += mp[i] * v[3 * i];
        vm[1] += mp[i] * v[3 * i + 1];
        vm[2] += mp[i] * v[3 * i + 2];
      }
#ifdef TELEOP_HAVE_AVX2_PATH
    }
#endif
  }
  double vmx = vm[0], vmy = vm[1], vmz = vm[2];
  const double alpha = p.mass_damping_per_s;
  const double inv_total = 1.0 / m.total_mass_kg;
  vmx = (vmx + m.centre_mass_kg * cv[0]) * inv_total;
  vmy = (vmy + m.centre_mass_kg * cv[1]) * inv_total;
  vmz = (vmz + m.centre_mass_kg * cv[2]) * inv_total;

  // the centre node: it moves on the radial springs' reaction only (no node reads it after the
  // force pass, so it may move before the nodes do)
  const double vmean[3] = {vmx, vmy, vmz};
  const auto move_centre = [&](const Internal& internal) {
    if (m.has_centre) symplectic_centre(m, s, h, cv, vmean, internal.centre);
  };

#ifdef TELEOP_HAVE_AVX2_PATH
  if (s.pinned_count == 0 && use_avx2()) {
    // steps 2 and 3 in flat passes; the next sub-step's pack in the position pass (step 3b is
    // not fused into the force loop: it would hold more live registers there, and is slower).
    const double gp[3] = {p.gravity_mps2.x() + alpha * vmx, p.gravity_mps2.y() + alpha * vmy,
                          p.gravity_mps2.z() + alpha * vmz};
    move_centre(internal_forces_avx2(m, s));
    NextPack next{{s.centre_x.x(), s.centre_x.y(), s.centre_x.z()},
                  {s.centre_v.x(), s.centre_v.y(), s.centre_v.z()},
                  {0.0, 0.0, 0.0}};
    integrate_flat_avx2(m, s, h, gp, loads_zero, sums, pack_next ? &next : nullptr);
    if (pack_next) {
      s.simd_vm[0] = next.vm[0];
      s.simd_vm[1] = next.vm[1];
      s.simd_vm[2] = next.vm[2];
      s.simd_pack_fresh = true;
    }
    return;
  }
  const Internal internal =
      use_avx2() ? internal_forces_avx2(m, s) : internal_forces_portable(m, s);
#else
  const Internal internal = internal_forces_portable(m, s);
#endif
  integrate_nodes(m, s, h, vmx, vmy, vmz, sums);
  move_centre(internal);
}

}  // namespace teleop::sim::deformable::detail
