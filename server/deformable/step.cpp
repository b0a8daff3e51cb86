// Forces, integrators, sleeping and fault handling of the deformable body. Nothing here
// allocates: every buffer lives in DeformableState and was sized by make_state().
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>

#include "server/deformable/deformable.hpp"
#include "server/deformable/fem.hpp"
#include "server/deformable/kernels.hpp"
#include "server/deformable/rotation.hpp"

// Not under the sanitizers: their instrumentation of the ifunc resolvers runs before the
// sanitizer runtime is initialised and crashes the program at load time.
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && \
    !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
#define TELEOP_HOT_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define TELEOP_HOT_CLONES
#endif

// For the helpers of the hot functions: inlined into every clone, so each one keeps the
// instruction set of its caller (a call to a separate baseline copy would lose AVX2 and FMA).
#if defined(__GNUC__)
#define TELEOP_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define TELEOP_ALWAYS_INLINE inline
#endif

namespace teleop::sim::deformable {

namespace {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;
using detail::abs_of;
using detail::extract_rotation;
using detail::load4;
using detail::quaternion_matrix;
using detail::rotation_step;
using detail::store4;
using detail::V4;
using detail::V4i;
using detail::V4u;

/// What compute_forces adds.
struct ForceFlags {
  bool external = true;         ///< gravity, drag, f_ext
  bool contact = true;          ///< plane penalties and friction
  bool jacobian = false;        ///< fill the blocks for the implicit solve
  int rotation_iterations = 8;  ///< co-rotational: polar-decomposition iterations per node (max)
  double rotation_tolerance_rad = 1e-7;  ///< co-rotational: stop when the increment is smaller
};

// out = 1 / sqrt(in) for squared lengths, a loop the compiler vectorises (-fno-math-errno; a
// max() would stop it). The 1e-30 is below the rounding of any real length but keeps a zero
// length finite (1e15 m^-1, multiplied by a zero vector).
TELEOP_HOT_CLONES __attribute__((optimize("O3"))) void inverse_sqrt(const double* __restrict in,
                                                                    double* __restrict out,
                                                                    int count) {
  for (int k = 0; k < count; ++k) out[k] = 1.0 / std::sqrt(in[k] + 1e-30);
}

// Co-rotational frames: per node, the rotation of its one-ring (plus the direction to the
// centroid, so that a nearly flat ring still fixes all three axes).
TELEOP_ALWAYS_INLINE void update_rotations(const DeformableModel& m, DeformableState& s,
                                           int max_iterations, double tolerance_rad) {
  const double* X = m.mesh.vertices.data();
  const double* x = s.x.data();
  const int n = m.node_count;
  double c[3] = {0.0, 0.0, 0.0}, c0[3] = {0.0, 0.0, 0.0}, msum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double mi = m.mass_kg(i);
    for (int k = 0; k < 3; ++k) {
      c[k] += mi * x[3 * i + k];
      c0[k] += mi * X[3 * i + k];
    }
    msum += mi;
  }
  const double inv = 1.0 / msum;
  for (int k = 0; k < 3; ++k) {
    c[k] *= inv;
    c0[k] *= inv;
  }
  const auto& off = m.mesh.vertex_neighbour_offsets;
  const auto& nb = m.mesh.vertex_neighbours;
  double* rot = s.rotation.front().data();  // n column-major 3 x 3 blocks, contiguous
  for (int i = 0; i < n; ++i) {
    double a[9] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    const double* xi = x + 3 * i;
    const double* Xi = X + 3 * i;
    double len2 = 0.0;
    for (int k = off[static_cast<std::size_t>(i)]; k < off[static_cast<std::size_t>(i) + 1]; ++k) {
      const int j = nb[static_cast<std::size_t>(k)];
      const double* xj = x + 3 * j;
      const double* Xj = X + 3 * j;
      const double D[3] = {Xj[0] - Xi[0], Xj[1] - Xi[1], Xj[2] - Xi[2]};
      const double d[3] = {xj[0] - xi[0], xj[1] - xi[1], xj[2] - xi[2]};
      for (int col = 0; col < 3; ++col) {
        a[3 * col] += d[0] * D[col];
        a[3 * col + 1] += d[1] * D[col];
        a[3 * col + 2] += d[2] * D[col];
      }
      len2 += D[0] * D[0] + D[1] * D[1] + D[2] * D[2];
    }
    const double rX[3] = {Xi[0] - c0[0], Xi[1] - c0[1], Xi[2] - c0[2]};
    const double r2 = rX[0] * rX[0] + rX[1] * rX[1] + rX[2] * rX[2];
    if (r2 > 0.0) {
      const double wgt = len2 / r2;
      const double rx[3] = {wgt * (xi[0] - c[0]), wgt * (xi[1] - c[1]), wgt * (xi[2] - c[2])};
      for (int col = 0; col < 3; ++col) {
        a[3 * col] += rx[0] * rX[col];
        a[3 * col + 1] += rx[1] * rX[col];
        a[3 * col + 2] += rx[2] * rX[col];
      }
    }
    extract_rotation(a, s.rotation_q[static_cast<std::size_t>(i)], max_iterations, tolerance_rad,
                     rot + 9 * i);
  }
}

// Gravity, drag and the caller's loads into s.work_f (every node; column N too if there is a
// centre node). The drag is relative to the mean velocity: it damps deformation, keeps momentum.
TELEOP_ALWAYS_INLINE void set_external_forces(const DeformableModel& m, DeformableState& s) {
  const int n = m.node_count;
  const DeformableParams& p = m.params;
  Eigen::Matrix3Xd& F = s.work_f;
  const Eigen::Matrix3Xd& v = s.v;
  const double alpha = p.mass_damping_per_s;
  Vec3 vcm = Vec3::Zero();
  if (alpha > 0.0) vcm = (v * m.mass_kg + m.centre_mass_kg * s.centre_v) / m.total_mass_kg;
  for (int i = 0; i < n; ++i) {
    F.col(i) = m.mass_kg(i) * (p.gravity_mps2 - alpha * (v.col(i) - vcm)) + s.f_ext.col(i);
  }
  if (m.has_centre) F.col(n) = m.centre_mass_kg * (p.gravity_mps2 - alpha * (s.centre_v - vcm));
}

// Mass-spring edge forces into s.edge_force (the force on each edge's first node), and with
// flags.jacobian the blocks for the implicit solve.
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
    // Eigen's 2+1-lane handling of 3-vectors (shuffles for every dot product) cost more
    // than it saved here
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
      const double k = kp[e];
      const double fs = k * ((dx * dx + dy * dy + dz * dz) * inv_l - l0[e]) + beta * k * rate;
      fp[3 * e] = fs * ux;
      fp[3 * e + 1] = fs * uy;
      fp[3 * e + 2] = fs * uz;
    }
    return;
  }
  for (int e = 0; e < ne; ++e) {
    const int i = m.edges(0, e), j = m.edges(1, e);
    const Vec3 d = x.col(j) - x.col(i);
    const double inv_l = inv_len(e);
    const Vec3 u = d * inv_l;
    const double k = m.edge_k_iso(e);
    const double c = beta * k;
    const double fs =
        k * (d.squaredNorm() * inv_l - m.rest_length_m(e)) + c * (v.col(j) - v.col(i)).dot(u);
    const Vec3 f = fs * u;
    Fe.col(e) = f;
    if (flags.jacobian) {
      // clamped spring Jacobian: the transverse term only when stretched (keeps it SPD)
      const double kt = k * std::max(0.0, 1.0 - m.rest_length_m(e) * inv_l);
      s.edge_dir.col(e) = u;
      s.edge_coef.col(e) << kt, k - kt, 0.0, c;
    }
  }
}

// Linear Navier edge forces into s.edge_force, and with flags.jacobian the implicit blocks.
TELEOP_ALWAYS_INLINE void navier_linear_edge_forces(const DeformableModel& m, DeformableState& s,
                                                    ForceFlags flags) {
  const int ne = static_cast<int>(m.edges.cols());
  const Eigen::Matrix3Xd& x = s.x;
  const Eigen::Matrix3Xd& v = s.v;
  const Eigen::Matrix3Xd& X = m.mesh.vertices;
  const double beta = m.params.stiffness_damping_s;
  for (int e = 0; e < ne; ++e) {
    const int i = m.edges(0, e), j = m.edges(1, e);
    const Vec3 u0 = m.rest_dir.col(e);
    const Vec3 strain = (x.col(j) - x.col(i)) - (X.col(j) - X.col(i));
    const Vec3 g = strain + beta * (v.col(j) - v.col(i));
    const double a = m.edge_k_iso(e), b = m.edge_k_dir(e);
    const Vec3 f = a * g + (b * g.dot(u0)) * u0;
    s.edge_force.col(e) = f;
    if (flags.jacobian) {
      s.edge_dir.col(e) = u0;
      s.edge_coef.col(e) << a, b, beta * a, beta * b;
    }
  }
}

// Co-rotational Navier edge forces into s.edge_force (the frames updated first) and the implicit
// blocks (implicit Euler; the explicit and symplectic steps take corotational_edges below).
TELEOP_ALWAYS_INLINE void navier_corotational_edge_forces(const DeformableModel& m,
                                                          DeformableState& s, ForceFlags flags) {
  const int ne = static_cast<int>(m.edges.cols());
  const Eigen::Matrix3Xd& x = s.x;
  const Eigen::Matrix3Xd& v = s.v;
  const Eigen::Matrix3Xd& X = m.mesh.vertices;
  const double beta = m.params.stiffness_damping_s;
  // warm-started: a few iterations per step track the motion; a cold query converges
  update_rotations(m, s, flags.rotation_iterations, flags.rotation_tolerance_rad);
  for (int e = 0; e < ne; ++e) {
    const int i = m.edges(0, e), j = m.edges(1, e);
    const Mat3 r =
        0.5 * (s.rotation[static_cast<std::size_t>(i)] + s.rotation[static_cast<std::size_t>(j)]);
    const Vec3 u0 = m.rest_dir.col(e);
    // hand-written 3x3 products (Eigen does not inline these mixed expressions here)
    const Vec3 q = (x.col(j) - x.col(i)) + beta * (v.col(j) - v.col(i));
    const Vec3 g = Vec3(r.col(0).dot(q), r.col(1).dot(q), r.col(2).dot(q)) - (X.col(j) - X.col(i));
    const double a = m.edge_k_iso(e), b = m.edge_k_dir(e);
    const Vec3 loc = a * g + (b * g.dot(u0)) * u0;
    const Vec3 f = r.col(0) * loc.x() + r.col(1) * loc.y() + r.col(2) * loc.z();
    s.edge_force.col(e) = f;
    s.edge_dir.col(e) = (r * u0).normalized();
    s.edge_coef.col(e) << a, b, beta * a, beta * b;
  }
}

// --- co-rotational Navier, explicit and symplectic path ---------------------------------------
// Four doubles at a time with GCC's vector extensions: 3-vectors padded to 4 lanes (AVX2 in the
// x86-64-v3 clone, two SSE2 halves in the default one). Per node, the positions relative to the
// centroid and the damped positions x - c + beta v are packed (4 + 4 doubles), the ring matrix is
// built column by column from the model's rest tables, and its rotation is extracted as before
// (warm-started, scalar); the frame is stored as columns and rows. Per edge, R = (R_i + R_j) / 2
// from both, R^T q from the rows and R loc from the columns: no horizontal work but the one dot
// product g . D.

// Positions relative to the mass-weighted centroid into s.corot_pack (4 doubles per node, from 0),
// and q = (x - c) + beta v, the damped positions of the edge forces (4 per node, from 4 n).
TELEOP_ALWAYS_INLINE void pack_corotational(const DeformableModel& m, DeformableState& s) {
  const int n = m.node_count;
  const double* x = s.x.data();
  const double* v = s.v.data();
  double c[3] = {0.0, 0.0, 0.0}, msum = 0.0;
  for (int i = 0; i < n; ++i) {
    const double mi = m.mass_kg(i);
    for (int k = 0; k < 3; ++k) c[k] += mi * x[3 * i + k];
    msum += mi;
  }
  const double inv = 1.0 / msum;
  for (int k = 0; k < 3; ++k) c[k] *= inv;
  const double beta = m.params.stiffness_damping_s;
  double* p = s.corot_pack.data();
  double* pq = p + 4 * static_cast<std::ptrdiff_t>(n);
  for (int i = 0; i < n; ++i) {
    double* pi = p + 4 * i;
    double* qi = pq + 4 * i;
    for (int k = 0; k < 3; ++k) {
      pi[k] = x[3 * i + k] - c[k];
      qi[k] = pi[k] + beta * v[3 * i + k];
    }
    pi[3] = qi[3] = 0.0;
  }
}

// Rows a, b, c, d of a 4 x 4 block to its columns.
TELEOP_ALWAYS_INLINE void transpose4(V4& a, V4& b, V4& c, V4& d) {
  const V4 t0 = __builtin_shuffle(a, b, V4i{0, 4, 1, 5});
  const V4 t1 = __builtin_shuffle(a, b, V4i{2, 6, 3, 7});
  const V4 t2 = __builtin_shuffle(c, d, V4i{0, 4, 1, 5});
  const V4 t3 = __builtin_shuffle(c, d, V4i{2, 6, 3, 7});
  a = __builtin_shuffle(t0, t2, V4i{0, 1, 4, 5});
  b = __builtin_shuffle(t0, t2, V4i{2, 3, 6, 7});
  c = __builtin_shuffle(t1, t3, V4i{0, 1, 4, 5});
  d = __builtin_shuffle(t1, t3, V4i{2, 3, 6, 7});
}

// Node i's ring matrix A_i as its three columns (x, y, z, 0).
TELEOP_ALWAYS_INLINE void ring_matrix(const DeformableModel& m, const double* p, int i, V4& a0,
                                      V4& a1, V4& a2) {
  const int w = m.corot_width;
  const V4 yi = load4(p + 4 * i);
  const double* e = m.corot_node_e.data() + 3 * i;
  a0 = yi * e[0];
  a1 = yi * e[1];
  a2 = yi * e[2];
  const int* nb = m.corot_nb.data();
  const double* rest = m.corot_ring_rest.data();
  for (int k = i * w; k < (i + 1) * w; ++k) {  // same length for every node (padded)
    const V4 yj = load4(p + 4 * nb[k]);
    const double* d = rest + 3 * k;
    a0 += yj * d[0];
    a1 += yj * d[1];
    a2 += yj * d[2];
  }
}

// The ring matrices of nodes i .. i + 3 (i a multiple of 4) in lanes: a[3 c + r] = A_rc, one node
// per lane, from the lane tables (the same sums in the same order as ring_matrix, per lane).
TELEOP_ALWAYS_INLINE void ring_matrix4(const DeformableModel& m, const double* p, int i, V4* a) {
  const int w = m.corot_width;
  const int* nb = m.corot_nb.data() + i * w;
  const double* e = m.corot_node_e4.data() + 3 * i;  // 12 per group of 4
  const double* rest = m.corot_ring_rest4.data() + 3 * i * w;
  const double* pi = p + 4 * i;
  V4 y0 = load4(pi), y1 = load4(pi + 4), y2 = load4(pi + 8), y3 = load4(pi + 12);
  transpose4(y0, y1, y2, y3);  // y0: x of the four nodes, y1: y, y2: z
  for (int c = 0; c < 3; ++c) {
    const V4 ec = load4(e + 4 * c);
    a[3 * c] = y0 * ec;
    a[3 * c + 1] = y1 * ec;
    a[3 * c + 2] = y2 * ec;
  }
  for (int k = 0; k < w; ++k) {
    V4 z0 = load4(p + 4 * nb[k]), z1 = load4(p + 4 * nb[w + k]), z2 = load4(p + 4 * nb[2 * w + k]),
       z3 = load4(p + 4 * nb[3 * w + k]);
    transpose4(z0, z1, z2, z3);
    const double* d = rest + 12 * k;
    for (int c = 0; c < 3; ++c) {
      const V4 dc = load4(d + 4 * c);
      a[3 * c] += z0 * dc;
      a[3 * c + 1] += z1 * dc;
      a[3 * c + 2] += z2 * dc;
    }
  }
}

// R / 2 as columns then rows, each padded to 4 (an edge's frame (R_i + R_j) / 2 is one sum).
TELEOP_ALWAYS_INLINE void store_frame(double* f, const double* r) {
  store4(f, 0.5 * V4{r[0], r[1], r[2], 0.0});
  store4(f + 4, 0.5 * V4{r[3], r[4], r[5], 0.0});
  store4(f + 8, 0.5 * V4{r[6], r[7], r[8], 0.0});
  store4(f + 12, 0.5 * V4{r[0], r[3], r[6], 0.0});
  store4(f + 16, 0.5 * V4{r[1], r[4], r[7], 0.0});
  store4(f + 20, 0.5 * V4{r[2], r[5], r[8], 0.0});
}

// extract_rotation for four nodes at once (lanes; a[9] their ring matrices, q[4] their warm
// starts), in the common case only: every lane has converged at the check or converges by one
// Newton step below 0.05 rad whose square is within the tolerance. The same arithmetic as one
// iteration of extract_rotation. Returns false, having changed nothing, when some lane is not
// in that case (the caller takes the scalar path for the four).
TELEOP_ALWAYS_INLINE bool newton_step4(const V4* a, V4* q, double tolerance_rad, V4* r) {
  quaternion_matrix(q[0], q[1], q[2], q[3], r);
  V4 ox, oy, oz;
  V4i newton;
  rotation_step(a, r, ox, oy, oz, newton);
  const V4 w2 = ox * ox + oy * oy + oz * oz;
  const V4i converged = !(w2 > tolerance_rad * tolerance_rad);
  const V4i ok = converged | (newton & (w2 < 0.05 * 0.05) & (w2 <= tolerance_rad));
  if (!(ok[0] && ok[1] && ok[2] && ok[3])) return false;
  // q <- dq * q with dq = (1, d / 2), normalised, where not converged
  const V4 dx = 0.5 * ox, dy = 0.5 * oy, dz = 0.5 * oz;
  const V4 nw = q[0] - dx * q[1] - dy * q[2] - dz * q[3];
  const V4 nx = q[1] + dx * q[0] + dy * q[3] - dz * q[2];
  const V4 ny = q[2] - dx * q[3] + dy * q[0] + dz * q[1];
  const V4 nz = q[3] + dx * q[2] - dy * q[1] + dz * q[0];
  // 1 / |q| to first order about 1: |q|^2 = 1 + |d|^2 / 4 (q was a unit quaternion) with
  // |d|^2 / 4 <= tolerance / 4 here, so the neglected term, 3/8 (|q|^2 - 1)^2, is below 1e-15
  // (for the default tolerance 1e-7 rad: 2.3e-16, the rounding of a double)
  const V4 n2 = nw * nw + nx * nx + ny * ny + nz * nz;
  const V4 inv_norm = 1.5 - 0.5 * n2;
  q[0] = converged ? q[0] : nw * inv_norm;
  q[1] = converged ? q[1] : nx * inv_norm;
  q[2] = converged ? q[2] : ny * inv_norm;
  q[3] = converged ? q[3] : nz * inv_norm;
  V4 rn[9];
  quaternion_matrix(q[0], q[1], q[2], q[3], rn);
  for (int k = 0; k < 9; ++k) r[k] = converged ? r[k] : rn[k];
  return true;
}

// Every node's frame from its ring matrix, into s.corot_frame (and s.rotation, for the energy
// and the next warm start). Four nodes at a time where one Newton step settles all four
// (newton_step4), else (and for the last n mod 4 nodes) node by node with extract_rotation.
TELEOP_ALWAYS_INLINE void corotational_frames(const DeformableModel& m, DeformableState& s,
                                              int max_iterations, double tolerance_rad) {
  const int n = m.node_count;
  const double* p = s.corot_pack.data();
  double* frame = s.corot_frame.data();
  double* rot = s.rotation.front().data();
  Eigen::Quaterniond* qs = s.rotation_q.data();
  const auto scalar_node = [&](int i, const double* a) {
    extract_rotation(a, qs[i], max_iterations, tolerance_rad, rot + 9 * i);
    store_frame(frame + 24 * i, rot + 9 * i);
  };
  int i = 0;
  for (; i + 4 <= n && max_iterations >= 1; i += 4) {
    V4 a[9];  // a[3 c + r] = A_rc of the four nodes
    ring_matrix4(m, p, i, a);
    // the four warm starts into lanes (Eigen stores a quaternion as x, y, z, w)
    V4 qx = load4(qs[i].coeffs().data()), qy = load4(qs[i + 1].coeffs().data()),
       qz = load4(qs[i + 2].coeffs().data()), qw = load4(qs[i + 3].coeffs().data());
    transpose4(qx, qy, qz, qw);
    V4 q[4] = {qw, qx, qy, qz};
    V4 r[9];
    if (!newton_step4(a, q, tolerance_rad, r)) {
      for (int l = 0; l < 4; ++l) {
        const double al[9] = {a[0][l], a[1][l], a[2][l], a[3][l], a[4][l],
                              a[5][l], a[6][l], a[7][l], a[8][l]};
        scalar_node(i + l, al);
      }
      continue;
    }
    // back to one node per vector: columns c[k][l] and rows w[k][l] of R / 2 for node i + l
    const V4 zero = {0.0, 0.0, 0.0, 0.0};
    V4 c[3][4], w[3][4];
    for (int k = 0; k < 3; ++k) {
      c[k][0] = 0.5 * r[3 * k];
      c[k][1] = 0.5 * r[3 * k + 1];
      c[k][2] = 0.5 * r[3 * k + 2];
      c[k][3] = zero;
      transpose4(c[k][0], c[k][1], c[k][2], c[k][3]);
      w[k][0] = 0.5 * r[k];
      w[k][1] = 0.5 * r[3 + k];
      w[k][2] = 0.5 * r[6 + k];
      w[k][3] = zero;
      transpose4(w[k][0], w[k][1], w[k][2], w[k][3]);
    }
    V4 q0 = q[1], q1 = q[2], q2 = q[3], q3 = q[0];  // back to x, y, z, w per node
    transpose4(q0, q1, q2, q3);
    store4(qs[i].coeffs().data(), q0);
    store4(qs[i + 1].coeffs().data(), q1);
    store4(qs[i + 2].coeffs().data(), q2);
    store4(qs[i + 3].coeffs().data(), q3);
    for (int l = 0; l < 4; ++l) {
      double* f = frame + 24 * (i + l);
      for (int k = 0; k < 3; ++k) {
        store4(f + 4 * k, c[k][l]);
        store4(f + 12 + 4 * k, w[k][l]);
      }
      // the full matrix (2 R / 2, exact) into s.rotation: two overlapping stores, then 3 values
      double* rl = rot + 9 * (i + l);
      store4(rl, 2.0 * c[0][l]);
      store4(rl + 3, 2.0 * c[1][l]);
      rl[6] = 2.0 * c[2][l][0];
      rl[7] = 2.0 * c[2][l][1];
      rl[8] = 2.0 * c[2][l][2];
    }
  }
  for (; i < n; ++i) {
    V4 a0, a1, a2;
    ring_matrix(m, p, i, a0, a1, a2);
    const double a[9] = {a0[0], a0[1], a0[2], a1[0], a1[1], a1[2], a2[0], a2[1], a2[2]};
    scalar_node(i, a);
  }
}

// Edge forces f = R (a g + b (g . u0) u0), g = R^T q - D, q = (x_j - x_i) + beta (v_j - v_i),
// R = (R_i + R_j) / 2, with (g . u0) u0 = (g . D) D / |D|^2 (the model's table holds D and
// 1 / |D|^2: 4 doubles per edge, where D and u0 took 8; with q packed per node, 3 % faster at
// levels 4 and 5). Node by node over the edges whose first node it is (the edges are sorted by
// first node, i < j): node i's pack and frame stay in registers, the force is summed for i and
// its reaction subtracted from j's accumulator (acc, 4 doubles per node, zero before node 0).
// When node i is reached every edge where it is the second node has been counted: the return
// value is node i's complete edge force (x, y, z, 0). (Before, each edge's force went to an array
// and every node gathered its incident edges with signs: 5 % slower at level 4.)
TELEOP_ALWAYS_INLINE V4 corotational_node_edges(const DeformableModel& m, const DeformableState& s,
                                                int i, double* __restrict acc) {
  const double* __restrict pq = s.corot_pack.data() + 4 * static_cast<std::ptrdiff_t>(m.node_count);
  const double* __restrict frame = s.corot_frame.data();
  const double* __restrict ed = m.corot_edge.data();
  const int* __restrict ep = m.edges.data();
  const int* __restrict first = m.first_edge_offsets.data();
  const double* __restrict ka = m.edge_k_iso.data();
  const double* __restrict kb = m.edge_k_dir.data();
  const double* fi = frame + 24 * i;
  const V4 ci0 = load4(fi), ci1 = load4(fi + 4), ci2 = load4(fi + 8);
  const V4 ri0 = load4(fi + 12), ri1 = load4(fi + 16), ri2 = load4(fi + 20);
  const V4 qi = load4(pq + 4 * i);
  V4 sum = {0.0, 0.0, 0.0, 0.0};
  for (int e = first[i]; e < first[i + 1]; ++e) {
    const int j = ep[2 * e + 1];
    const double* fj = frame + 24 * j;
    const V4 q = load4(pq + 4 * j) - qi;
    // the frames hold R / 2 (corotational_frames): their sum is R
    const V4 t = (ri0 + load4(fj + 12)) * q[0] + (ri1 + load4(fj + 16)) * q[1] +
                 (ri2 + load4(fj + 20)) * q[2];
    // lane 3: t has 0 (the rows are padded with 0), D has 1 / |D|^2; g, gd and loc carry
    // values there that nothing reads
    const V4 d = load4(ed + 4 * e);
    const V4 g = t - d;
    const V4 gd = g * d;
    const double bg = (kb[e] * ed[4 * e + 3]) * (gd[0] + gd[1] + gd[2]);
    const V4 loc = ka[e] * g + bg * d;
    const V4 f = (ci0 + load4(fj)) * loc[0] + (ci1 + load4(fj + 4)) * loc[1] +
                 (ci2 + load4(fj + 8)) * loc[2];
    sum += f;
    store4(acc + 4 * j, load4(acc + 4 * j) - f);
  }
  return sum + load4(acc + 4 * i);
}

// Every node's edge forces (corotational_node_edges) added to s.work_f (the explicit step).
TELEOP_ALWAYS_INLINE void corotational_edges(const DeformableModel& m, DeformableState& s) {
  const int n = m.node_count;
  double* acc = s.corot_force.data();
  std::fill(acc, acc + 4 * static_cast<std::size_t>(n), 0.0);
  double* fp = s.work_f.data();
  for (int i = 0; i < n; ++i) {
    const V4 sum = corotational_node_edges(m, s, i, acc);
    fp[3 * i] += sum[0];
    fp[3 * i + 1] += sum[1];
    fp[3 * i + 2] += sum[2];
  }
}

// Adds to s.work_f, per node, the forces of its incident edges from s.edge_force (+ on an
// edge's first node, - on its second): a gather per node instead of a scatter per edge.
TELEOP_ALWAYS_INLINE void gather_edge_forces(const DeformableModel& m, DeformableState& s) {
  const int n = m.node_count;
  const auto& off = m.node_edge_offsets;
  const auto& inc = m.node_edges;
  const double* fe = s.edge_force.data();
  double* fp = s.work_f.data();
  for (int i = 0; i < n; ++i) {
    double sx = 0.0, sy = 0.0, sz = 0.0;
    for (int k = off[static_cast<std::size_t>(i)]; k < off[static_cast<std::size_t>(i) + 1]; ++k) {
      const int code = inc[static_cast<std::size_t>(k)];  // e (first node) or ~e (second)
      const int c = 3 * (code >= 0 ? code : ~code);
      const double sign = code >= 0 ? 1.0 : -1.0;
      sx += sign * fe[c];
      sy += sign * fe[c + 1];
      sz += sign * fe[c + 2];
    }
    fp[3 * i] += sx;
    fp[3 * i + 1] += sy;
    fp[3 * i + 2] += sz;
  }
}

// Adds the radial springs between the nodes and the centre node to s.work_f (the reactions to
// column N), and with flags.jacobian stores their implicit blocks. Needs m.has_centre.
TELEOP_ALWAYS_INLINE void add_radial_forces(const DeformableModel& m, DeformableState& s,
                                            ForceFlags flags) {
  const int n = m.node_count;
  const DeformableParams& p = m.params;
  Eigen::Matrix3Xd& F = s.work_f;
  const Eigen::Matrix3Xd& x = s.x;
  const Eigen::Matrix3Xd& v = s.v;
  Vec3 fc = Vec3::Zero();
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
      const double l = (dx * dx + dy * dy + dz * dz) * inv_l;
      const double rate = (vp[a] - cvx) * ux + (vp[a + 1] - cvy) * uy + (vp[a + 2] - cvz) * uz;
      const double k = kr[i];
      const double fs = -k * (l - r0[i]) - rd * k * rate;
      fp[a] += fs * ux;
      fp[a + 1] += fs * uy;
      fp[a + 2] += fs * uz;
      fcx -= fs * ux;
      fcy -= fs * uy;
      fcz -= fs * uz;
    }
    F.col(n) += Vec3(fcx, fcy, fcz);
    return;
  }
  for (int i = 0; i < n; ++i) {
    const Vec3 d = x.col(i) - s.centre_x;
    const double inv_l = inv_len(i);
    const Vec3 u = d * inv_l;
    const double l = d.squaredNorm() * inv_l;
    const double k = m.radial_k(i);
    const double c = p.radial_damping_s * k;
    const double fs = -k * (l - m.radial_rest_m(i)) - c * (v.col(i) - s.centre_v).dot(u);
    F.col(i) += fs * u;
    fc -= fs * u;
    if (flags.jacobian) {
      const double kt = k * std::max(0.0, 1.0 - m.radial_rest_m(i) * inv_l);
      s.radial_dir.col(i) = u;
      s.radial_coef.col(i) << kt, k - kt, 0.0, c;
    }
  }
  F.col(n) += fc;
}

// Node-plane penalty contact: records every contact (s.contact_*) and adds its force to
// s.work_f. Implicit Euler (flags.jacobian): spring, damping and (rate-limited) Coulomb
// friction as forces here, damping also in its matrix. Explicit/symplectic Euler: only the
// spring here; damping and friction are applied implicitly per node in apply_contact_impulses()
// (an explicit damper on a light node next to the stability limit of the membrane would not be
// stable).
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
      const Vec3 vi = v.col(i);
      const double vn = pl.normal.dot(vi);
      double fn = spring - m.contact_c(i) * vn;
      if (fn < 0.0) fn = 0.0;  // a wall pushes, never pulls
      Vec3 f = fn * pl.normal;
      if (p.friction && pl.friction > 0.0) {
        const Vec3 vt = vi - vn * pl.normal;
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

// Total force on every node (and the centre node, column N) into s.work_f at (s.x, s.v).
// Compiled twice, for x86-64-v3 (AVX2, FMA) and for the baseline; the loader picks the one the
// CPU supports (GCC function multi-versioning), so the binary still runs on any x86-64. The
// helpers above are always inlined, so each copy has its own.
TELEOP_HOT_CLONES
void compute_forces(const DeformableModel& m, DeformableState& s, double h, ForceFlags flags) {
  const int n = m.node_count;
  if (!flags.external) s.work_f.setZero();
  s.work_f.col(n).setZero();
  if (flags.external) set_external_forces(m, s);  // gravity, drag and the caller's loads

  // edges, in two passes: the force of each edge (on its first node; the second node gets
  // the opposite), then a gather per node over its incident edges. Independent iterations
  // instead of a scatter whose read-modify-write chains serialise the loop.
  switch (m.params.model) {
    case ModelKind::kMassSpring:
      mass_spring_edge_forces(m, s, flags);
      break;
    case ModelKind::kNavierLinear:
      navier_linear_edge_forces(m, s, flags);
      break;
    case ModelKind::kNavierCorotational:
      if (!flags.jacobian) {
        // explicit and symplectic: the vector path, which gathers its own edge forces
        pack_corotational(m, s);
        corotational_frames(m, s, flags.rotation_iterations, flags.rotation_tolerance_rad);
        corotational_edges(m, s);
      } else {
        navier_corotational_edge_forces(m, s, flags);
      }
      break;
    case ModelKind::kFem:
      break;  // fem_step (fem.cpp) computes its own forces
  }
  if (m.params.model != ModelKind::kNavierCorotational || flags.jacobian) {
    gather_edge_forces(m, s);
  }

  // radial springs to the centre node
  if (m.has_centre) add_radial_forces(m, s, flags);

  // node-plane penalty contact
  s.contact_count = 0;
  s.plane_force_n.setZero();
  if (flags.contact && m.plane_count > 0) add_plane_contacts(m, s, h, flags);
}

// Explicit and symplectic Euler: contact damping and Coulomb friction as velocity impulses,
// after the velocity update (implicit in the damping, so stable for any damping ratio):
//   v_n <- v_n / (1 + h c / m), never pulling (total normal impulse >= 0);
//   tangential impulse <= mu * normal impulse, and never more than stops the sliding.
// One contact of a node of mass `mass` with plane normal `nrm`, damper `damping`, the spring's
// impulse h * k * depth and friction `mu`: returns the new velocity, adds the force to `total`.
inline Vec3 contact_impulse(const Vec3& nrm, double mass, double damping, double spring_impulse,
                            double mu, double h, Vec3 vi, Vec3& total) {
  const double vn = nrm.dot(vi);
  double dvn = vn / (1.0 + h * damping / mass) - vn;
  dvn = std::max(dvn, -spring_impulse / mass);
  vi += dvn * nrm;
  const double jn = spring_impulse + mass * dvn;  // >= 0
  Vec3 impulse = jn * nrm;
  if (mu > 0.0) {
    const Vec3 vt = vi - nrm.dot(vi) * nrm;
    const double st = vt.norm();
    if (st > 1e-12) {
      const double jt = std::min(mu * jn, mass * st);
      vi -= (jt / (mass * st)) * vt;
      impulse -= (jt / st) * vt;
    }
  }
  total += impulse / h;
  return vi;
}

TELEOP_HOT_CLONES
void apply_contact_impulses(const DeformableModel& m, DeformableState& s, double h) {
  for (int c = 0; c < s.contact_count; ++c) {
    const int i = s.contact_node[static_cast<std::size_t>(c)];
    if (s.pinned_count > 0 && s.pinned[static_cast<std::size_t>(i)]) continue;
    s.v.col(i) = contact_impulse(s.contact_normal.col(c), m.mass_kg(i), s.contact_coef(1, c),
                                 h * s.contact_coef(2, c), s.contact_coef(3, c), h, s.v.col(i),
                                 s.plane_force_n);
  }
}

// Nodes per block of the fused mass-spring step (about 100 edges: their data stays in L1).
constexpr int kFusedNodeBlock = 32;

// What the post-step checks need, gathered while the nodes are visited.
struct NodeSums {
  double fastest2 = 0.0;   ///< largest squared node speed
  double sum_x = 0.0;      ///< sum of all coordinates (NaN and infinity propagate)
  double sum_v = 0.0;      ///< sum of squared speeds (NaN and infinity propagate)
  Vec3 mx = Vec3::Zero();  ///< sum of m_i x_i over the surface nodes
};

// Mean velocity of the body, centre node included, into vm (x, y, z) for the drag (relative to
// it: damps deformation, keeps momentum); left at zero without drag.
TELEOP_ALWAYS_INLINE void drag_mean_velocity(const DeformableModel& m, const DeformableState& s,
                                             double vm[3]) {
  const int n = m.node_count;
  const double* __restrict v = s.v.data();
  const double* __restrict mp = m.mass_kg.data();
  double vmx = 0.0, vmy = 0.0, vmz = 0.0;
  if (m.params.mass_damping_per_s > 0.0) {
    for (int i = 0; i < n; ++i) {
      vmx += mp[i] * v[3 * i];
      vmy += mp[i] * v[3 * i + 1];
      vmz += mp[i] * v[3 * i + 2];
    }
    const double inv_total = 1.0 / m.total_mass_kg;
    vmx = (vmx + m.centre_mass_kg * s.centre_v.x()) * inv_total;
    vmy = (vmy + m.centre_mass_kg * s.centre_v.y()) * inv_total;
    vmz = (vmz + m.centre_mass_kg * s.centre_v.z()) * inv_total;
  }
  vm[0] = vmx;
  vm[1] = vmy;
  vm[2] = vmz;
}

// For the nodes b0..b1-1: the squared lengths of their edges (into s.edge_length2) and of their
// radial springs (s.node_length2), then 1 / length of all (s.edge_scratch, s.node_scratch;
// vectorised), while the positions are still the old ones.
TELEOP_ALWAYS_INLINE void fused_block_lengths(const DeformableModel& m, DeformableState& s, int b0,
                                              int b1) {
  const double* __restrict x = s.x.data();
  const int* __restrict j3 = m.second_node3.data();
  const int* __restrict first = m.first_edge_offsets.data();
  double* __restrict l2 = s.edge_length2.data();
  double* __restrict rl2 = s.node_length2.data();
  const double cx = s.centre_x.x(), cy = s.centre_x.y(), cz = s.centre_x.z();
  for (int i = b0; i < b1; ++i) {
    const double xx = x[3 * i], xy = x[3 * i + 1], xz = x[3 * i + 2];
    for (int e = first[i]; e < first[i + 1]; ++e) {
      const int j = j3[e];
      const double dx = x[j] - xx, dy = x[j + 1] - xy, dz = x[j + 2] - xz;
      l2[e] = dx * dx + dy * dy + dz * dz;
    }
    const double dx = xx - cx, dy = xy - cy, dz = xz - cz;
    rl2[i] = dx * dx + dy * dy + dz * dz;
  }
  inverse_sqrt(l2 + first[b0], s.edge_scratch.data() + first[b0], first[b1] - first[b0]);
  if (m.has_centre) inverse_sqrt(rl2 + b0, s.node_scratch.data() + b0, b1 - b0);
}

// The edge springs (i, j), j > i, of node i at (xx, xy, xz) moving at (vx, vy, vz): their force
// on i added to (fx, fy, fz), their reactions onto the nodes j in f.
TELEOP_ALWAYS_INLINE void fused_node_edges(const DeformableModel& m, const DeformableState& s,
                                           int i, const double* __restrict x,
                                           const double* __restrict v, double* __restrict f,
                                           double xx, double xy, double xz, double vx, double vy,
                                           double vz, double& fx, double& fy, double& fz) {
  const int* __restrict j3 = m.second_node3.data();
  const int* __restrict first = m.first_edge_offsets.data();
  const double* __restrict kp = m.edge_k_iso.data();
  const double* __restrict l0 = m.rest_length_m.data();
  const double* __restrict l2 = s.edge_length2.data();
  const double* __restrict il = s.edge_scratch.data();
  const double beta = m.params.stiffness_damping_s;
  for (int e = first[i]; e < first[i + 1]; ++e) {
    const int j = j3[e];
    const double dx = x[j] - xx, dy = x[j + 1] - xy, dz = x[j + 2] - xz;
    const double inv_l = il[e];
    const double ux = dx * inv_l, uy = dy * inv_l, uz = dz * inv_l;
    const double rate = (v[j] - vx) * ux + (v[j + 1] - vy) * uy + (v[j + 2] - vz) * uz;
    const double k = kp[e];
    const double fs = k * (l2[e] * inv_l - l0[e]) + beta * k * rate;
    const double ex = fs * ux, ey = fs * uy, ez = fs * uz;
    fx += ex;
    fy += ey;
    fz += ez;
    f[j] -= ex;
    f[j + 1] -= ey;
    f[j + 2] -= ez;
  }
}

// The radial spring of node i at (xx, xy, xz) moving at (vx, vy, vz) to the centre node at c
// moving at cv: its force added to (fx, fy, fz), the reaction to fc.
TELEOP_ALWAYS_INLINE void fused_node_radial(const DeformableModel& m, const DeformableState& s,
                                            int i, const double c[3], const double cv[3], double xx,
                                            double xy, double xz, double vx, double vy, double vz,
                                            double& fx, double& fy, double& fz, double fc[3]) {
  const double* __restrict kr = m.radial_k.data();
  const double* __restrict r0 = m.radial_rest_m.data();
  const double* __restrict rl2 = s.node_length2.data();
  const double* __restrict rl = s.node_scratch.data();
  const double rd = m.params.radial_damping_s;
  const double dx = xx - c[0], dy = xy - c[1], dz = xz - c[2];
  const double inv_l = rl[i];
  const double ux = dx * inv_l, uy = dy * inv_l, uz = dz * inv_l;
  const double rate = (vx - cv[0]) * ux + (vy - cv[1]) * uy + (vz - cv[2]) * uz;
  const double fs = -kr[i] * (rl2[i] * inv_l - r0[i]) - rd * kr[i] * rate;
  fx += fs * ux;
  fy += fs * uy;
  fz += fs * uz;
  fc[0] -= fs * ux;
  fc[1] -= fs * uy;
  fc[2] -= fs * uz;
}

// The plane penalty springs of node i at (xx, xy, xz): their force added to (fx, fy, fz), each
// spring force into spring_of[k], the count into nc; returns the planes touched (bit k: inside
// plane k).
TELEOP_ALWAYS_INLINE unsigned fused_node_plane_springs(const DeformableModel& m, int i, double xx,
                                                       double xy, double xz, double spring_of[8],
                                                       double& fx, double& fy, double& fz,
                                                       int& nc) {
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

// The contact impulses of node i (mass mi) on the planes it touches, applied to (vx, vy, vz) in
// plane order; the planes' forces added to plane_force.
TELEOP_ALWAYS_INLINE void fused_node_impulses(const DeformableModel& m, int i, double mi, double h,
                                              unsigned touched, const double spring_of[8],
                                              double& vx, double& vy, double& vz,
                                              Vec3& plane_force) {
  const double* __restrict cc = m.contact_c.data();
  for (int k = 0; touched != 0 && k < m.plane_count; ++k) {
    if ((touched & (1u << k)) == 0) continue;
    const Plane& pl = m.planes[static_cast<std::size_t>(k)];
    const Vec3 vi =
        contact_impulse(pl.normal, mi, cc[i], h * spring_of[k],
                        m.params.friction ? pl.friction : 0.0, h, Vec3(vx, vy, vz), plane_force);
    vx = vi.x();
    vy = vi.y();
    vz = vi.z();
  }
}

// The hot path of the default body: mass-spring with symplectic Euler in one pass over the
// nodes. Equivalent to compute_forces() + integrate(): the same forces, and per node the same
// velocity update, contact impulses and position update. It relies on the edges being sorted by
// first node (i < j): node i's own edges (i, j) are one range, visited with node i; their
// reactions are added to the later nodes j, whose edges to earlier nodes are then complete. So
// when node i is reached its force is complete, and no later edge reads x_i or v_i: node i can
// be advanced at once. 1 / length of the edges of a block of nodes is computed first, in a
// vectorised loop, while those positions are still the old ones. The helpers above are always
// inlined, so each clone keeps its own instruction set.
TELEOP_HOT_CLONES
void step_mass_spring_symplectic(const DeformableModel& m, DeformableState& s, double h,
                                 NodeSums& sums) {
  const int n = m.node_count;
  const DeformableParams& p = m.params;
  double* __restrict x = s.x.data();
  double* __restrict v = s.v.data();
  double* __restrict f = s.force.data();  // edge reactions from earlier nodes, then the total
  const double* __restrict mp = m.mass_kg.data();
  const double* __restrict imp = m.inv_mass.data();
  const double* __restrict fext = s.f_ext.data();
  const double* __restrict tgt = s.pin_target.data();
  const std::uint8_t* __restrict pin = s.pinned.data();
  std::fill(f, f + 3 * n, 0.0);

  double vm[3];
  drag_mean_velocity(m, s, vm);
  const double vmx = vm[0], vmy = vm[1], vmz = vm[2];
  const double alpha = p.mass_damping_per_s;
  const double c[3] = {s.centre_x.x(), s.centre_x.y(), s.centre_x.z()};
  const double cv[3] = {s.centre_v.x(), s.centre_v.y(), s.centre_v.z()};
  const double gx = p.gravity_mps2.x(), gy = p.gravity_mps2.y(), gz = p.gravity_mps2.z();
  const bool centre = m.has_centre;
  const bool any_pinned = s.pinned_count > 0;
  double fc[3] = {0.0, 0.0, 0.0};  // the radial springs' reaction on the centre node
  double spring_of[8] = {};        // spring force of each plane; valid where `touched` has its bit
  int nc = 0;
  Vec3 plane_force = Vec3::Zero();
  double fastest2 = 0.0, sum_x = 0.0, sum_v = 0.0, mxx = 0.0, mxy = 0.0, mxz = 0.0;

  for (int b0 = 0; b0 < n; b0 += kFusedNodeBlock) {
    const int b1 = std::min(n, b0 + kFusedNodeBlock);
    fused_block_lengths(m, s, b0, b1);
    for (int i = b0; i < b1; ++i) {
      const int a = 3 * i;
      const double mi = mp[i];
      const double xx = x[a], xy = x[a + 1], xz = x[a + 2];
      double vx = v[a], vy = v[a + 1], vz = v[a + 2];
      // edge springs (i, j), j > i: the force on i here, the reaction onto j
      double fx = 0.0, fy = 0.0, fz = 0.0;
      fused_node_edges(m, s, i, x, v, f, xx, xy, xz, vx, vy, vz, fx, fy, fz);
      // gravity, drag and the caller's load
      fx += f[a] + mi * (gx - alpha * (vx - vmx)) + fext[a];
      fy += f[a + 1] + mi * (gy - alpha * (vy - vmy)) + fext[a + 1];
      fz += f[a + 2] + mi * (gz - alpha * (vz - vmz)) + fext[a + 2];
      // radial spring to the centre node
      if (centre) fused_node_radial(m, s, i, c, cv, xx, xy, xz, vx, vy, vz, fx, fy, fz, fc);
      // plane penalty springs (damping and friction below, as impulses)
      const unsigned touched =
          fused_node_plane_springs(m, i, xx, xy, xz, spring_of, fx, fy, fz, nc);
      f[a] = fx;
      f[a + 1] = fy;
      f[a + 2] = fz;
      // symplectic Euler: velocity (held nodes keep theirs), contact impulses, position
      const bool held = any_pinned && pin[i] != 0;
      if (!held) {
        const double hm = h * imp[i];
        vx += hm * fx;
        vy += hm * fy;
        vz += hm * fz;
        fused_node_impulses(m, i, mi, h, touched, spring_of, vx, vy, vz, plane_force);
      }
      double px = xx + h * vx, py = xy + h * vy, pz = xz + h * vz;
      if (held) {
        px = tgt[a];
        py = tgt[a + 1];
        pz = tgt[a + 2];
      }
      v[a] = vx;
      v[a + 1] = vy;
      v[a + 2] = vz;
      x[a] = px;
      x[a + 1] = py;
      x[a + 2] = pz;
      const double sp2 = vx * vx + vy * vy + vz * vz;
      fastest2 = sp2 > fastest2 ? sp2 : fastest2;
      sum_x += px + py + pz;
      sum_v += sp2;  // NaN and infinity propagate into the sums
      mxx += mi * px;
      mxy += mi * py;
      mxz += mi * pz;
    }
  }
  s.contact_count = nc;
  s.plane_force_n = plane_force;
  if (centre) {
    const double hm = h / m.centre_mass_kg, mc = m.centre_mass_kg;
    s.centre_v.x() += hm * (mc * (gx - alpha * (cv[0] - vmx)) + fc[0]);
    s.centre_v.y() += hm * (mc * (gy - alpha * (cv[1] - vmy)) + fc[1]);
    s.centre_v.z() += hm * (mc * (gz - alpha * (cv[2] - vmz)) + fc[2]);
    s.centre_x += h * s.centre_v;
  }
  sums.fastest2 = fastest2;
  sums.sum_x = sum_x;
  sums.sum_v = sum_v;
  sums.mx = Vec3(mxx, mxy, mxz);
}

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
    const Vec3 w = s.edge_dir.col(e);
    const double si = cc * co(2) + kc * co(0), sd = cc * co(3) + kc * co(1);
    const Vec3 d = pv.col(i) - pv.col(j);
    const Vec3 y = si * d + (sd * w.dot(d)) * w;
    out.col(i) += y;
    out.col(j) -= y;
  }
  if (m.has_centre) {
    Vec3 yc = Vec3::Zero();
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector4d co = s.radial_coef.col(i);
      const Vec3 w = s.radial_dir.col(i);
      const double si = cc * co(2) + kc * co(0), sd = cc * co(3) + kc * co(1);
      const Vec3 d = pv.col(i) - pv.col(n);
      const Vec3 y = si * d + (sd * w.dot(d)) * w;
      out.col(i) += y;
      yc -= y;
    }
    out.col(n) += yc;
  }
  for (int c = 0; c < s.contact_count; ++c) {
    const int i = s.contact_node[static_cast<std::size_t>(c)];
    const Vec3 nrm = s.contact_normal.col(c);
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
    const Vec3 w = s.edge_dir.col(e);
    const Vec3 dd =
        Vec3::Constant(h * co(2) + h2 * co(0)) + (h * co(3) + h2 * co(1)) * w.cwiseProduct(w);
    dg.col(m.edges(0, e)) += dd;
    dg.col(m.edges(1, e)) += dd;
  }
  if (m.has_centre) {
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector4d co = s.radial_coef.col(i);
      const Vec3 w = s.radial_dir.col(i);
      const Vec3 dd =
          Vec3::Constant(h * co(2) + h2 * co(0)) + (h * co(3) + h2 * co(1)) * w.cwiseProduct(w);
      dg.col(i) += dd;
      dg.col(n) += dd;
    }
  }
  for (int c = 0; c < s.contact_count; ++c) {
    const Vec3 nrm = s.contact_normal.col(c);
    dg.col(s.contact_node[static_cast<std::size_t>(c)]) +=
        (h * s.contact_coef(1, c) + h2 * s.contact_coef(0, c)) * nrm.cwiseProduct(nrm);
  }
  if (!m.has_centre) dg.col(n).setOnes();  // unused column: keep it well defined
  dg = dg.cwiseInverse();                  // stored inverted: CG multiplies
}

// Integration of positions and velocities by the chosen scheme; s.work_f holds the forces.
TELEOP_HOT_CLONES
void integrate(const DeformableModel& m, DeformableState& s, double h) {
  const int n = m.node_count;
  const auto kind = m.params.integrator;
  if (kind == IntegratorKind::kExplicitEuler) {
    for (int i = 0; i < n; ++i) {
      s.x.col(i) += h * s.v.col(i);
      if (!s.pinned[static_cast<std::size_t>(i)])
        s.v.col(i) += (h * m.inv_mass(i)) * s.work_f.col(i);
    }
    apply_contact_impulses(m, s, h);
    if (m.has_centre) {
      s.centre_x += h * s.centre_v;
      s.centre_v += (h / m.centre_mass_kg) * s.work_f.col(n);
    }
    return;
  }
  if (kind == IntegratorKind::kSymplecticEuler) {
    for (int i = 0; i < n; ++i) {
      if (!s.pinned[static_cast<std::size_t>(i)])
        s.v.col(i) += (h * m.inv_mass(i)) * s.work_f.col(i);
    }
    apply_contact_impulses(m, s, h);
    for (int i = 0; i < n; ++i) s.x.col(i) += h * s.v.col(i);
    if (m.has_centre) {
      s.centre_v += (h / m.centre_mass_kg) * s.work_f.col(n);
      s.centre_x += h * s.centre_v;
    }
    return;
  }
  // linearly implicit Euler: (M + hC + h^2 K) dv = h (f - h K v), Jacobi-preconditioned CG
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
  Eigen::Matrix3Xd& dv = s.work_dv;
  Eigen::Matrix3Xd& r = s.work_r;
  Eigen::Matrix3Xd& z = s.work_z;
  Eigen::Matrix3Xd& pp = s.work_p;
  Eigen::Matrix3Xd& ap = s.work_ap;
  dv.setZero();
  r = b;
  z = r.cwiseProduct(s.work_diag);
  pp = z;
  double rz = (r.array() * z.array()).sum();
  const double rz0 = rz;
  const double tol2 = m.params.cg_tolerance * m.params.cg_tolerance;
  int it = 0;
  const double h2 = h * h;
  while (it < m.params.cg_max_iterations && rz > tol2 * rz0 && rz0 > 0.0) {
    apply_system(m, s, pp, ap, 1.0, h, h2);
    const double pap = (pp.array() * ap.array()).sum();
    if (!(pap > 0.0)) break;
    const double alpha = rz / pap;
    dv += alpha * pp;
    r -= alpha * ap;
    z = r.cwiseProduct(s.work_diag);
    const double rz_new = (r.array() * z.array()).sum();
    pp = z + (rz_new / rz) * pp;
    rz = rz_new;
    ++it;
  }
  s.cg_iterations = it;
  s.cg_residual = rz0 > 0.0 ? std::sqrt(std::max(rz, 0.0) / rz0) : 0.0;
  for (int i = 0; i < n; ++i) {
    if (!s.pinned[static_cast<std::size_t>(i)]) s.v.col(i) += dv.col(i);
    s.x.col(i) += h * s.v.col(i);
  }
  if (m.has_centre) {
    s.centre_v += dv.col(n);
    s.centre_x += h * s.centre_v;
  }
}

// One pass over the caller's loads, on their bits (vectorised): all finite? all zero (+-0)?
struct LoadScan {
  bool finite = true;
  bool zero = true;
};
TELEOP_HOT_CLONES __attribute__((optimize("O3"))) LoadScan scan_loads(const Eigen::Matrix3Xd& f) {
  constexpr std::uint64_t kExponent = 0x7ff0000000000000ull;
  const double* d = f.data();
  const Eigen::Index count = f.size();
  std::uint64_t non_finite = 0, bits = 0;
  for (Eigen::Index k = 0; k < count; ++k) {
    std::uint64_t b;
    std::memcpy(&b, d + k, sizeof b);
    non_finite |= static_cast<std::uint64_t>((b & kExponent) == kExponent);
    bits |= b << 1;  // drops the sign: -0 counts as zero
  }
  return {non_finite == 0, bits == 0};
}

bool loaded(const DeformableModel& m, const DeformableState& s, bool loads_zero) {
  if (s.wake_request) return true;
  if (!loads_zero) return true;
  for (int i = 0; i < m.state_node_count(); ++i) {
    if (s.pinned[static_cast<std::size_t>(i)] && s.pin_target.col(i) != s.x.col(i)) return true;
  }
  return false;
}

void reset_to_rest(const DeformableModel& m, DeformableState& s) {
  if (m.params.model == ModelKind::kFem) {
    const Vec3 shift = s.last_good_centroid - m.rest_centre_m;
    s.x = m.fem.rest;
    s.x.colwise() += shift;
    s.v.setZero();
    for (int i = 0; i < m.fem.node_count; ++i) {
      if (s.pinned[static_cast<std::size_t>(i)] && s.pin_target.col(i).allFinite()) {
        s.x.col(i) = s.pin_target.col(i);
      }
    }
    for (int t = 0; t < m.fem.tet_count; ++t) {
      double* q = s.fem_q.data() + 4 * t;
      q[0] = 1.0;
      q[1] = q[2] = q[3] = 0.0;
    }
    s.still_time_s = 0.0;
    return;
  }
  const Vec3 shift =
      s.last_good_centroid -
      (m.mesh.vertices * m.mass_kg + m.centre_mass_kg * m.rest_centre_m) / m.total_mass_kg;
  s.x = m.mesh.vertices;
  s.x.colwise() += shift;
  s.v.setZero();
  s.centre_x = m.rest_centre_m + shift;
  s.centre_v.setZero();
  for (int i = 0; i < m.node_count; ++i) {
    if (s.pinned[static_cast<std::size_t>(i)] && s.pin_target.col(i).allFinite()) {
      s.x.col(i) = s.pin_target.col(i);
    }
    s.rotation[static_cast<std::size_t>(i)].setIdentity();
    s.rotation_q[static_cast<std::size_t>(i)].setIdentity();
  }
  s.still_time_s = 0.0;
}

}  // namespace

void internal_forces(const DeformableModel& m, DeformableState& s, Eigen::Matrix3Xd& out) {
  if (m.params.model == ModelKind::kFem) {
    detail::fem_internal_forces(m, s, 200, 1e-13);
    if (out.cols() != m.fem.node_count) out.resize(3, m.fem.node_count);
    out = s.work_f.leftCols(m.fem.node_count);
    return;
  }
  ForceFlags flags;
  flags.external = false;
  flags.contact = false;
  flags.rotation_iterations = 200;
  flags.rotation_tolerance_rad = 1e-13;
  compute_forces(m, s, 1.0, flags);
  if (out.cols() != m.node_count) out.resize(3, m.node_count);
  out = s.work_f.leftCols(m.node_count);
}

namespace {

// Held nodes: sets the velocity that takes each one to its target in this step (a non-finite
// target releases the node) and counts them (s.pinned_count, the released ones included).
// Returns whether any held node moves.
TELEOP_ALWAYS_INLINE bool drive_held_nodes(const DeformableModel& m, DeformableState& s, double h) {
  bool pin_moving = false;
  s.pinned_count = 0;
  const std::uint8_t* flags = s.pinned.data();
  const int nodes = m.state_node_count();
  for (int i = 0; i < nodes; ++i) {
    if (i + 8 <= nodes) {  // eight flags at once: usually no node is held
      std::uint64_t word;
      std::memcpy(&word, flags + i, sizeof word);
      if (word == 0) {
        i += 7;
        continue;
      }
    }
    if (!flags[i]) continue;
    ++s.pinned_count;
    if (!s.pin_target.col(i).allFinite()) {
      s.pinned[static_cast<std::size_t>(i)] = 0;  // a bad target releases the node
      continue;
    }
    s.v.col(i) = (s.pin_target.col(i) - s.x.col(i)) / h;
    pin_moving = pin_moving || s.pin_target.col(i) != s.x.col(i);
  }
  return pin_moving;
}

// The fault event of a blow-up: names the first non-finite node, else the fastest one (largest
// squared speed fastest2 [m^2/s^2]).
TELEOP_ALWAYS_INLINE void report_blow_up(const DeformableModel& m, const DeformableState& s,
                                         double fastest2, bool finite,
                                         teleop::sim::EventQueue& events) {
  int fastest = 0;
  for (int i = 0; i < m.state_node_count(); ++i) {
    const double sp2 = s.v.col(i).squaredNorm();
    if (!std::isfinite(sp2) || !s.x.col(i).allFinite()) {
      fastest = i;
      fastest2 = sp2;
      break;
    }
    if (sp2 >= fastest2) fastest = i;
  }
  char msg[128];
  std::snprintf(msg, sizeof(msg),
                "deformable: blow-up (node %d speed %.3g m/s%s); reset to rest shape", fastest,
                std::sqrt(fastest2), finite ? "" : ", NaN");
  events.push(EventKind::kFault, Severity::kError, s.sim_time_s, std::sqrt(fastest2), msg);
}

TELEOP_HOT_CLONES
StepStatus step_impl(const DeformableModel& m, DeformableState& s, double h,
                     teleop::sim::EventQueue* events, bool allow_fused, LoadScan loads,
                     bool more_substeps = false, double tip_alpha = 1.0) {
  const int n = m.node_count;
  if (!(h > 0.0) || !std::isfinite(h) || !loads.finite) {
    if (events) {
      events->push(EventKind::kFault, Severity::kWarning, s.sim_time_s, h,
                   "deformable: step refused (dt <= 0 or non-finite, or non-finite f_ext)");
    }
    return StepStatus::kBadInput;
  }
  if (s.sleeping) {
    if (!loaded(m, s, loads.zero)) {
      s.sim_time_s += h;
      ++s.sleeping_steps;
      return StepStatus::kSleeping;
    }
    s.sleeping = false;
    s.still_time_s = 0.0;
  }
  s.wake_request = false;

  // held nodes: the velocity that takes them to their target in this step
  const bool pin_moving = drive_held_nodes(m, s, h);

  NodeSums sums;
  if (m.params.model == ModelKind::kFem) {
    detail::KernelSums ks;
    detail::fem_step(m, s, h, tip_alpha, ks);
    sums.fastest2 = ks.fastest2;
    sums.sum_x = ks.sum_x;
    sums.sum_v = ks.sum_v;
    sums.mx = Vec3(ks.mx[0], ks.mx[1], ks.mx[2]);
  } else if (allow_fused && m.params.kernel == KernelKind::kSimd) {
    detail::KernelSums ks;
    detail::step_mass_spring_simd(m, s, h, loads.zero, more_substeps, ks);
    sums.fastest2 = ks.fastest2;
    sums.sum_x = ks.sum_x;
    sums.sum_v = ks.sum_v;
    sums.mx = Vec3(ks.mx[0], ks.mx[1], ks.mx[2]);
  } else if (allow_fused && m.params.model == ModelKind::kMassSpring &&
             m.params.integrator == IntegratorKind::kSymplecticEuler) {
    step_mass_spring_symplectic(m, s, h, sums);
  } else {
    ForceFlags flags;
    flags.jacobian = m.params.integrator == IntegratorKind::kImplicitEuler;
    compute_forces(m, s, h, flags);
    s.force = s.work_f.leftCols(n);
    integrate(m, s, h);
    // one pass: held nodes onto their targets, fastest node, finiteness, centroid
    for (int i = 0; i < n; ++i) {
      if (s.pinned_count > 0 && s.pinned[static_cast<std::size_t>(i)]) {
        s.x.col(i) = s.pin_target.col(i);
      }
      const double sp2 = s.v.col(i).squaredNorm();
      sums.fastest2 = sp2 > sums.fastest2 ? sp2 : sums.fastest2;
      sums.sum_x += s.x.col(i).sum();
      sums.sum_v += sp2;  // NaN and infinity propagate into the sums
      sums.mx += m.mass_kg(i) * s.x.col(i);
    }
  }
  s.sim_time_s += h;
  ++s.steps;
  const double vmax2 = m.params.max_speed_mps * m.params.max_speed_mps;
  const double fastest2 = sums.fastest2;
  const double sum_x = sums.sum_x, sum_v = sums.sum_v;
  const Vec3 mx = sums.mx + m.centre_mass_kg * s.centre_x;
  const bool finite = std::isfinite(sum_x) && std::isfinite(sum_v) && s.centre_x.allFinite() &&
                      s.centre_v.allFinite();
  if (!finite || !(fastest2 <= vmax2) || !(s.centre_v.squaredNorm() <= vmax2)) {
    ++s.fault_count;
    if (events) report_blow_up(m, s, fastest2, finite, *events);
    reset_to_rest(m, s);
    s.simd_pack_fresh = false;
    return StepStatus::kFaultReset;
  }
  s.last_good_centroid = mx / m.total_mass_kg;

  // sleeping: still, unloaded and no held node moving for sleep_time_s
  const double sleep2 = m.params.sleep_speed_mps * m.params.sleep_speed_mps;
  const bool tip_present = m.params.model == ModelKind::kFem && s.tip_radius_m > 0.0;
  if (fastest2 < sleep2 && s.centre_v.squaredNorm() < sleep2 && !pin_moving && loads.zero &&
      !tip_present) {
    s.still_time_s += h;
    if (s.still_time_s >= m.params.sleep_time_s) {
      s.sleeping = true;
      s.v.setZero();
      s.centre_v.setZero();
      s.simd_pack_fresh = false;  // the pack holds the velocities before this
    }
  } else {
    s.still_time_s = 0.0;
  }
  return StepStatus::kOk;
}

}  // namespace

namespace {

// dt split into n equal sub-steps of step_impl: the caller's loads are held, pinned nodes move
// linearly from where they are to their targets (each sub-step ends on its share of the way), the
// first fault or bad input ends the step. Allocation-free: the caller's targets are kept in
// s.pin_goal while the sub-steps overwrite s.pin_target.
// f_ext is the caller's and does not change during a step: scanned once (scan_loads) for all
// its sub-steps.
StepStatus step_substeps(const DeformableModel& m, DeformableState& s, double dt, int n,
                         teleop::sim::EventQueue* events, bool allow_fused) {
  const LoadScan loads = scan_loads(s.f_ext);
  s.simd_pack_fresh = false;  // x and v may have been changed since the last call
  const double h = dt / n;
  if (!s.substeps_announced && events != nullptr && std::isfinite(dt)) {
    const int needed = m.substeps_needed(dt);
    char msg[128];
    if (needed < n) {  // params.min_substeps: accuracy, not stability
      std::snprintf(msg, sizeof(msg),
                    "deformable: %d sub-steps of %.3g ms (min_substeps, for accuracy; stable step "
                    "%.3g ms)",
                    n, h * 1e3, m.stable_step_s * 1e3);
    } else if (needed > n) {
      std::snprintf(msg, sizeof(msg),
                    "deformable: dt %.3g ms needs %d sub-steps, capped at %d (max_substeps): "
                    "may blow up",
                    dt * 1e3, needed, n);
    } else {
      std::snprintf(msg, sizeof(msg),
                    "deformable: dt %.3g ms > stable step %.3g ms (w_max %.0f rad/s): "
                    "%d sub-steps of %.3g ms",
                    dt * 1e3, m.stable_step_s * 1e3, m.omega_max_rad_per_s, n, h * 1e3);
    }
    events->push(EventKind::kInfo, needed > n ? Severity::kWarning : Severity::kInfo, s.sim_time_s,
                 static_cast<double>(n), msg);
    s.substeps_announced = true;
  }
  s.last_substeps = n;
  const int nodes = m.state_node_count();
  bool any_pin = false;  // eight flags at a time: usually no node is held
  const std::uint8_t* flags = s.pinned.data();
  int i0 = 0;
  for (; i0 + 8 <= nodes && !any_pin; i0 += 8) {
    std::uint64_t word;
    std::memcpy(&word, flags + i0, sizeof word);
    any_pin = word != 0;
  }
  for (; i0 < nodes && !any_pin; ++i0) any_pin = flags[i0] != 0;
  if (any_pin) {
    s.pin_goal = s.pin_target;  // same size: no allocation
    s.pin_start = s.x;          // where the held nodes start (same size: no allocation)
  }
  StepStatus result = StepStatus::kOk;
  for (int k = 1; k <= n; ++k) {
    if (any_pin) {
      const double frac = static_cast<double>(k) / n;
      for (int i = 0; i < nodes; ++i) {
        if (!s.pinned[static_cast<std::size_t>(i)]) continue;
        s.pin_target.col(i) =
            k == n ? Eigen::Vector3d(s.pin_goal.col(i))
                   : Eigen::Vector3d(s.pin_start.col(i) +
                                     frac * (s.pin_goal.col(i) - s.pin_start.col(i)));
      }
    }
    const StepStatus st =
        step_impl(m, s, h, events, allow_fused, loads, k < n, static_cast<double>(k) / n);
    if (st == StepStatus::kFaultReset || st == StepStatus::kBadInput) {
      result = st;
      break;
    }
    if (st == StepStatus::kSleeping) {
      s.sim_time_s += (n - k) * h;  // asleep for the rest of dt
      if (k == 1) result = st;
      break;
    }
  }
  if (any_pin) s.pin_target = s.pin_goal;
  s.simd_pack_fresh = false;  // never outlives the call
  return result;
}

}  // namespace

namespace {

StepStatus step_any(const DeformableModel& m, DeformableState& s, double h,
                    teleop::sim::EventQueue* events) {
  const int n = m.substeps_for(h);
  if (n <= 1) {
    s.last_substeps = 1;
    if (!(m.stable_step_s > 0.0) && !s.substeps_announced && events != nullptr) {
      events->push(EventKind::kInfo, Severity::kWarning, s.sim_time_s, 0.0,
                   "deformable: explicit Euler without damping is unstable at any step; use "
                   "symplectic_euler or implicit_euler");
      s.substeps_announced = true;
    }
    return step_impl(m, s, h, events, true, scan_loads(s.f_ext));
  }
  return step_substeps(m, s, h, n, events, true);
}

}  // namespace

StepStatus step(const DeformableModel& m, DeformableState& s, double h,
                teleop::sim::EventQueue* events) {
  if (m.params.model != ModelKind::kFem) return step_any(m, s, h, events);
  // the tip sphere's reaction: impulses summed over the sub-steps, then the mean force
  s.tip_force_n.setZero();
  s.tip_node_count = 0;
  s.tip_depth_m = 0.0;
  if (s.tip_radius_m > 0.0 && s.sleeping) wake(s);  // a tip near the body: it may be touched
  const StepStatus st = step_any(m, s, h, events);
  if (st == StepStatus::kOk && h > 0.0) {
    s.tip_force_n /= h;
  } else {
    s.tip_force_n.setZero();
  }
  return st;
}

StepStatus detail::step_general(const DeformableModel& m, DeformableState& s, double h,
                                teleop::sim::EventQueue* events) {
  const int n = m.substeps_for(h);
  if (n <= 1) {
    s.last_substeps = 1;
    return step_impl(m, s, h, events, false, scan_loads(s.f_ext));
  }
  return step_substeps(m, s, h, n, events, false);
}

StepStatus detail::step_once(const DeformableModel& m, DeformableState& s, double h,
                             teleop::sim::EventQueue* events) {
  s.last_substeps = 1;
  return step_impl(m, s, h, events, true, scan_loads(s.f_ext));
}

}  // namespace teleop::sim::deformable
