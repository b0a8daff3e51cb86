// The volumetric model (model fem): rest data, the co-rotated tetrahedron force law, implicit
// node contact with planes and the tip sphere, and the three integrators. See fem.hpp.
#include "server/deformable/fem.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

#include "server/deformable/conjugate_gradient.hpp"
#include "server/deformable/hot.hpp"
#include "server/deformable/integrators.hpp"
#include "server/deformable/rotation.hpp"

namespace teleop::sim::deformable::detail {

namespace {

using Vec3 = Eigen::Vector3d;

[[noreturn]] void bad(const std::string& what) {
  throw config::ConfigError("deformable parameters (model fem): " + what);
}

std::string number_text(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.4g", v);
  return b;
}

// Polar-decomposition iterations per element and step, and the increment at which they stop.
constexpr int kRotationIterations = 8;
constexpr double kRotationTolerance = 1e-7;

// c = a b for column-major 3x3 matrices (of one element, or of four: T = V4, one per lane).
template <class T>
TELEOP_ALWAYS_INLINE void mul33(const T* a, const T* b, T* c) {
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) {
      c[3 * j + i] = a[i] * b[3 * j] + a[3 + i] * b[3 * j + 1] + a[6 + i] * b[3 * j + 2];
    }
  }
}

// c = a^T b (column-major).
template <class T>
TELEOP_ALWAYS_INLINE void mul33_tn(const T* a, const T* b, T* c) {
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) {
      c[3 * j + i] =
          a[3 * i] * b[3 * j] + a[3 * i + 1] * b[3 * j + 1] + a[3 * i + 2] * b[3 * j + 2];
    }
  }
}

// The edge matrix [q1 - q0, q2 - q0, q3 - q0] (column-major) of the nodes `ix` of field q (3 x N).
TELEOP_ALWAYS_INLINE void edge_matrix(const double* q, const int* ix, double* d) {
  const double* q0 = q + 3 * ix[0];
  for (int c = 0; c < 3; ++c) {
    const double* qc = q + 3 * ix[c + 1];
    d[3 * c] = qc[0] - q0[0];
    d[3 * c + 1] = qc[1] - q0[1];
    d[3 * c + 2] = qc[2] - q0[2];
  }
}

// The edge matrices of four tetrahedra (node indices ix[l], one per lane) of field q (3 x N).
// Each vector is built from its four lanes' values at once (no lane-by-lane stores into vectors
// that are then reloaded whole).
TELEOP_ALWAYS_INLINE void edge_matrix4(const double* q, const int* const* ix, V4* d) {
  const double* p[4][4];  // [node k of the tet][lane l]
  for (int k = 0; k < 4; ++k) {
    for (int l = 0; l < 4; ++l) p[k][l] = q + 3 * ix[l][k];
  }
  for (int r = 0; r < 3; ++r) {
    const V4 base = {p[0][0][r], p[0][1][r], p[0][2][r], p[0][3][r]};
    for (int c = 0; c < 3; ++c) {
      const V4 qc = {p[c + 1][0][r], p[c + 1][1][r], p[c + 1][2][r], p[c + 1][3][r]};
      d[3 * c + r] = qc - base;
    }
  }
}

// Linear-elastic stress of the rotated gradient G (= R^T F - I, or its rate): sigma = 2 mu
// sym(G) + lambda tr(G) I, written symmetric into sig (column-major). scale_trace: G's trace
// offset (1 for R^T F, whose identity is subtracted here; 0 for a rate or a perturbation).
template <class T>
TELEOP_ALWAYS_INLINE void linear_stress(const T* g, double mu, double lambda, double identity,
                                        T* sig) {
  const T e00 = g[0] - identity, e11 = g[4] - identity, e22 = g[8] - identity;
  const T tr = e00 + e11 + e22;
  sig[0] = 2.0 * mu * e00 + lambda * tr;
  sig[4] = 2.0 * mu * e11 + lambda * tr;
  sig[8] = 2.0 * mu * e22 + lambda * tr;
  sig[1] = sig[3] = mu * (g[1] + g[3]);
  sig[2] = sig[6] = mu * (g[2] + g[6]);
  sig[5] = sig[7] = mu * (g[5] + g[7]);
}

// Adds the nodal forces of first Piola stress P (column-major) of a tetrahedron of volume vol
// and rest inverse B: f_j = -vol P B(j-1, :)^T for j = 1..3, f_0 = -(f_1 + f_2 + f_3); `sign`
// -1 gives K p instead (the force's negative).
TELEOP_ALWAYS_INLINE void scatter_forces(const double* p, const double* b, double vol,
                                         const int* ix, double sign, double* out) {
  double s0 = 0.0, s1 = 0.0, s2 = 0.0;
  for (int j = 0; j < 3; ++j) {
    // column j of P B^T: sum_k P(:, k) B(j, k)
    const double bj0 = b[j], bj1 = b[3 + j], bj2 = b[6 + j];
    const double hx = -sign * vol * (p[0] * bj0 + p[3] * bj1 + p[6] * bj2);
    const double hy = -sign * vol * (p[1] * bj0 + p[4] * bj1 + p[7] * bj2);
    const double hz = -sign * vol * (p[2] * bj0 + p[5] * bj1 + p[8] * bj2);
    double* o = out + 3 * ix[j + 1];
    o[0] += hx;
    o[1] += hy;
    o[2] += hz;
    s0 += hx;
    s1 += hy;
    s2 += hz;
  }
  double* o0 = out + 3 * ix[0];
  o0[0] -= s0;
  o0[1] -= s1;
  o0[2] -= s2;
}

// Average nodal pressure (Bonet and Burton's remedy for the volumetric locking of linear
// tetrahedra; params.nodal_pressure): the volumetric energy sum_a lambda/2 V_a theta_a^2 with
// theta_a the volume-weighted mean of the volumetric strains theta_e = tr(eps_e) of node a's
// tetrahedra, in place of each tetrahedron's own lambda/2 V_e theta_e^2. Its force on tetrahedron
// e's nodes is -V_e p_e R_e grad N_j with p_e = lambda (the mean of theta_a over e's four nodes)
// (exact: tr(R^T F) has no derivative through the polar factor R). `theta` holds theta_e per
// tetrahedron, `node_theta` is scratch (a value per node); `sign` -1 gives K p.
TELEOP_ALWAYS_INLINE void nodal_pressure_forces(const DeformableModel& m, const double* frames,
                                                const double* theta, double* node_theta,
                                                double sign, double* out) {
  const DeformableModel::Fem& f = m.fem;
  for (int i = 0; i < f.node_count; ++i) node_theta[i] = 0.0;
  for (int t = 0; t < f.tet_count; ++t) {
    const double w = 0.25 * f.volume_m3(t) * theta[t];
    for (int k = 0; k < 4; ++k) node_theta[f.tets(k, t)] += w;
  }
  for (int i = 0; i < f.node_count; ++i) node_theta[i] *= f.inv_node_volume(i);
  const double lambda = m.lame_lambda_pa;
  for (int t = 0; t < f.tet_count; ++t) {
    const int* ix = f.tets.col(t).data();
    const double pe =
        0.25 * lambda *
        (node_theta[ix[0]] + node_theta[ix[1]] + node_theta[ix[2]] + node_theta[ix[3]]);
    double p[9];
    const double* r = frames != nullptr ? frames + 9 * t : nullptr;
    for (int k = 0; k < 9; ++k) p[k] = r != nullptr ? pe * r[k] : (k % 4 == 0 ? pe : 0.0);
    scatter_forces(p, f.dm_inv.data() + 9 * t, f.volume_m3(t), ix, sign, out);
  }
}

// A second Newton step (the frames r of the quaternions q) for the lanes `step` of the lanes
// `redo`, those whose first step was a Newton step of less than 0.05 rad. Returns the lanes of
// `redo` still to finish: not stepped here, or whose second step was not a Newton step with a
// square below the tolerance.
TELEOP_ALWAYS_INLINE V4i second_step(const V4* fg, V4i step, V4i redo, double tolerance, V4& qw,
                                     V4& qx, V4& qy, V4& qz, V4* r) {
  V4 ox, oy, oz;
  V4i newton;
  rotation_step(fg, r, ox, oy, oz, newton);
  const V4 w2 = ox * ox + oy * oy + oz * oz;
  const V4i moved = step & (w2 > tolerance * tolerance);
  const V4 hx = 0.5 * ox, hy = 0.5 * oy, hz = 0.5 * oz;
  const V4 nw = qw - hx * qx - hy * qy - hz * qz;
  const V4 nx = qx + hx * qw + hy * qz - hz * qy;
  const V4 ny = qy - hx * qz + hy * qw + hz * qx;
  const V4 nz = qz + hx * qy - hy * qx + hz * qw;
  const V4 n2 = nw * nw + nx * nx + ny * ny + nz * nz;
  V4 inv;
  for (int l = 0; l < 4; ++l) inv[l] = 1.0 / std::sqrt(n2[l]);
  qw = moved ? nw * inv : qw;
  qx = moved ? nx * inv : qx;
  qy = moved ? ny * inv : qy;
  qz = moved ? nz * inv : qz;
  quaternion_matrix(qw, qx, qy, qz, r);
  return redo & ~(step & (newton != 0) & (w2 <= tolerance));
}

// The frames of tetrahedra t0 .. t0 + 3 (deformation gradients fg, one per lane) into r and
// s.fem_q / s.fem_r: one Newton step from the warm start in four lanes; a lane whose step is not
// converged after it (the increment's square above the tolerance, or no Newton step) is finished
// by the scalar iteration.
TELEOP_ALWAYS_INLINE void group_frames(DeformableState& s, int t0, const V4* fg, int iterations,
                                       double tolerance, bool keep_frames, V4* r) {
  // frames: one Newton step from the warm start in four lanes
  double* qd = s.fem_q.data() + 4 * t0;
  V4 qw = {qd[0], qd[4], qd[8], qd[12]}, qx = {qd[1], qd[5], qd[9], qd[13]},
     qy = {qd[2], qd[6], qd[10], qd[14]}, qz = {qd[3], qd[7], qd[11], qd[15]};
  quaternion_matrix(qw, qx, qy, qz, r);
  V4 ox, oy, oz;
  V4i newton;
  rotation_step(fg, r, ox, oy, oz, newton);
  const V4 w2 = ox * ox + oy * oy + oz * oz;
  const double tol2 = tolerance * tolerance;
  if (!(w2[0] <= tol2 && w2[1] <= tol2 && w2[2] <= tol2 && w2[3] <= tol2)) {
    // q <- (1, o / 2) q, normalised, where the increment is above the tolerance
    const V4 hx = 0.5 * ox, hy = 0.5 * oy, hz = 0.5 * oz;
    V4 nw = qw - hx * qx - hy * qy - hz * qz;
    V4 nx = qx + hx * qw + hy * qz - hz * qy;
    V4 ny = qy - hx * qz + hy * qw + hz * qx;
    V4 nz = qz + hx * qy - hy * qx + hz * qw;
    // 1 / |n| by two Newton steps from 1: exact to rounding for the lanes kept (|o| <= 3e-4
    // rad: |n|^2 - 1 ~ 1e-8); the others are redone by the scalar iteration below
    const V4 n2 = nw * nw + nx * nx + ny * ny + nz * nz;
    V4 inv = 1.5 - 0.5 * n2;
    inv = inv * (1.5 - 0.5 * n2 * inv * inv);
    const V4i moved = w2 > tol2;
    qw = moved ? nw * inv : qw;
    qx = moved ? nx * inv : qx;
    qy = moved ? ny * inv : qy;
    qz = moved ? nz * inv : qz;
    quaternion_matrix(qw, qx, qy, qz, r);
    // a Newton step leaves an error of the order of its square: the lanes above take a second
    // step in four lanes, and those it leaves are finished by the scalar iteration (a vector
    // test first: usually none is)
    V4i redo = (newton == 0) | (w2 > tolerance);
    if ((redo[0] | redo[1] | redo[2] | redo[3]) != 0) {
      redo =
          second_step(fg, redo & (newton != 0) & (w2 < 0.0025), redo, tolerance, qw, qx, qy, qz, r);
    }
    const bool any = (redo[0] | redo[1] | redo[2] | redo[3]) != 0;
    for (int l = 0; any && l < 4; ++l) {
      if (redo[l] == 0) continue;
      double a[9], rl[9];
      for (int k = 0; k < 9; ++k) a[k] = fg[k][l];
      Eigen::Quaterniond q(qw[l], qx[l], qy[l], qz[l]);
      q.normalize();  // the lanes' 1 / |n| is exact only for the small increments kept
      quaternion_matrix(q.w(), q.x(), q.y(), q.z(), rl);
      extract_rotation(a, q, iterations, tolerance, rl);
      qw[l] = q.w();
      qx[l] = q.x();
      qy[l] = q.y();
      qz[l] = q.z();
      for (int k = 0; k < 9; ++k) r[k][l] = rl[k];
    }
  }
  for (int l = 0; l < 4; ++l) {
    qd[4 * l] = qw[l];
    qd[4 * l + 1] = qx[l];
    qd[4 * l + 2] = qy[l];
    qd[4 * l + 3] = qz[l];
  }
  if (!keep_frames) return;
  double* rd = s.fem_r.data() + 9 * t0;
  for (int l = 0; l < 4; ++l) {
    for (int k = 0; k < 9; ++k) rd[9 * l + k] = r[k][l];
  }
}

// The frames of tetrahedra t0 .. t0 + 3 (one per lane) from their quaternions in s.fem_q.
TELEOP_ALWAYS_INLINE void group_frames_from_q(const DeformableState& s, int t0, V4* r) {
  const double* qd = s.fem_q.data() + 4 * t0;
  const V4 qw = {qd[0], qd[4], qd[8], qd[12]}, qx = {qd[1], qd[5], qd[9], qd[13]},
           qy = {qd[2], qd[6], qd[10], qd[14]}, qz = {qd[3], qd[7], qd[11], qd[15]};
  quaternion_matrix(qw, qx, qy, qz, r);
}

// The four lanes' (x[l], y[l], z[l], 0) of the component vectors x, y, z, one vector per lane.
TELEOP_ALWAYS_INLINE void lanes_xyz(V4 x, V4 y, V4 z, V4* out) {
  const V4 zero = {0.0, 0.0, 0.0, 0.0};
  // __builtin_shufflevector (GCC 12 and clang): lanes 0-3 of the first vector, 4-7 of the second
  const V4 xy02 = __builtin_shufflevector(x, y, 0, 4, 2, 6);
  const V4 xy13 = __builtin_shufflevector(x, y, 1, 5, 3, 7);
  const V4 z02 = __builtin_shufflevector(z, zero, 0, 4, 2, 6);
  const V4 z13 = __builtin_shufflevector(z, zero, 1, 5, 3, 7);
  out[0] = __builtin_shufflevector(xy02, z02, 0, 1, 4, 5);
  out[1] = __builtin_shufflevector(xy13, z13, 0, 1, 4, 5);
  out[2] = __builtin_shufflevector(xy02, z02, 2, 3, 6, 7);
  out[3] = __builtin_shufflevector(xy13, z13, 2, 3, 6, 7);
}

// Adds the node forces h (h[3 j + i]: component i on node j + 1 of the lane's tetrahedron; node 0
// takes minus their sum) of four tetrahedra to out, each node's three components as one vector of
// four whose last lane adds 0 to the next node's x: `out` holds one column past the last node.
TELEOP_ALWAYS_INLINE void scatter4(const V4* h, const int* const* ix, double* out) {
  V4 node[4][4];  // [node k of the tet][lane l]: (x, y, z, 0)
  for (int j = 0; j < 3; ++j) lanes_xyz(h[3 * j], h[3 * j + 1], h[3 * j + 2], node[j + 1]);
  lanes_xyz(-(h[0] + h[3] + h[6]), -(h[1] + h[4] + h[7]), -(h[2] + h[5] + h[8]), node[0]);
  for (int l = 0; l < 4; ++l) {
    for (int k : {1, 2, 3, 0}) {
      double* o = out + 3 * ix[l][k];
      store4(o, load4(o) + node[k][l]);
    }
  }
}

// h = -vol P B^T (nodes 1..3 of each lane; column-major P, B).
TELEOP_ALWAYS_INLINE void node_forces4(const V4* p, const V4* b, V4 vol, V4* h) {
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) {
      h[3 * j + i] = -vol * (p[i] * b[j] + p[3 + i] * b[3 + j] + p[6 + i] * b[6 + j]);
    }
  }
}

// The elastic and damping forces of tetrahedra 4g .. 4g + 3, one per lane: the arithmetic of the
// scalar loop below in four lanes (the frames: group_frames), added to out. With nodal pressure
// (`nodal`) these are the deviatoric forces and each tetrahedron's tr(eps) is added to its nodes'
// s.fem_node_theta (a quarter by volume);
// pressure_group adds the pressure's share once the nodes' pressures are known. The frames are
// kept in s.fem_r only when `keep_frames` (the implicit solve reads them); s.fem_q always.
TELEOP_ALWAYS_INLINE void element_group(const DeformableModel& m, DeformableState& s, int g,
                                        double beta, int iterations, double tolerance, bool nodal,
                                        bool keep_frames, double* out) {
  const DeformableModel::Fem& f = m.fem;
  const double mu = m.lame_mu_pa, lambda = nodal ? 0.0 : m.lame_lambda_pa;
  const int t0 = 4 * g;
  const int* ix[4] = {f.tets.col(t0).data(), f.tets.col(t0 + 1).data(), f.tets.col(t0 + 2).data(),
                      f.tets.col(t0 + 3).data()};
  V4 ds[9], b[9], fg[9];
  edge_matrix4(s.x.data(), ix, ds);
  const double* b4 = f.dm_inv4.data() + 36 * g;
  for (int k = 0; k < 9; ++k) b[k] = load4(b4 + 4 * k);
  mul33(ds, b, fg);
  V4 r[9];
  group_frames(s, t0, fg, iterations, tolerance, keep_frames, r);
  V4 gm[9], sig[9], p[9];
  if (beta > 0.0) {
    // R^T (F + beta F') = R^T (Ds + beta Dv) B
    V4 dv[9], fb[9];
    edge_matrix4(s.v.data(), ix, dv);
    for (int k = 0; k < 9; ++k) dv[k] = ds[k] + beta * dv[k];
    mul33(dv, b, fb);
    mul33_tn(r, fb, gm);
  } else {
    mul33_tn(r, fg, gm);  // R^T F
  }
  linear_stress(gm, mu, lambda, 1.0, sig);
  mul33(r, sig, p);  // P = R sigma
  const V4 vol = load4(f.volume4.data() + 4 * g);
  V4 h[9];
  node_forces4(p, b, vol, h);
  scatter4(h, ix, out);
  if (!nodal) return;
  // each tetrahedron's tr(eps) (+ rate), a quarter of it by volume to each of its nodes
  const V4 w = 0.25 * vol * (gm[0] + gm[4] + gm[8] - 3.0);
  double* node_theta = s.fem_node_theta.data();
  for (int l = 0; l < 4; ++l) {
    for (int k = 0; k < 4; ++k) node_theta[ix[l][k]] += w[l];
  }
}

// The pressure forces of tetrahedra 4g .. 4g + 3, p_e = lambda (mean of their nodes' theta_a,
// node_theta) times -vol R B^T (the force of a unit pressure), R from the quaternions the
// element pass left in s.fem_q: recomputed rather than kept, so the pass writes nothing per
// tetrahedron but its quaternion and tr(eps).
TELEOP_ALWAYS_INLINE void pressure_group(const DeformableModel& m, const DeformableState& s, int g,
                                         const double* node_theta, double* out) {
  const DeformableModel::Fem& f = m.fem;
  const int t0 = 4 * g;
  const int* ix[4] = {f.tets.col(t0).data(), f.tets.col(t0 + 1).data(), f.tets.col(t0 + 2).data(),
                      f.tets.col(t0 + 3).data()};
  V4 pe;
  for (int l = 0; l < 4; ++l) {
    pe[l] =
        node_theta[ix[l][0]] + node_theta[ix[l][1]] + node_theta[ix[l][2]] + node_theta[ix[l][3]];
  }
  pe *= 0.25 * m.lame_lambda_pa;
  V4 r[9], b[9], h[9];
  group_frames_from_q(s, t0, r);
  const double* b4 = f.dm_inv4.data() + 36 * g;
  for (int k = 0; k < 9; ++k) b[k] = load4(b4 + 4 * k);
  node_forces4(r, b, pe * load4(f.volume4.data() + 4 * g), h);
  scatter4(h, ix, out);
}

// Elastic and damping forces of every tetrahedron, added to out (3 x N): frames refreshed in
// s.fem_q / s.fem_r. Four at a time (element_group), the last tet_count % 4 one by one; with
// nodal pressure a second pass adds each tetrahedron's forces once its nodes' pressures are known.
TELEOP_HOT_CLONES
void element_forces(const DeformableModel& m, DeformableState& s, double beta, int iterations,
                    double tolerance, double* out) {
  const DeformableModel::Fem& f = m.fem;
  const bool nodal = m.params.nodal_pressure;
  const double mu = m.lame_mu_pa, lambda = nodal ? 0.0 : m.lame_lambda_pa;
  const double* x = s.x.data();
  const double* v = s.v.data();
  const int groups = f.tet_count / 4;
  const bool keep_frames = m.params.integrator == IntegratorKind::kImplicitEuler;
  if (nodal) std::fill(s.fem_node_theta.begin(), s.fem_node_theta.end(), 0.0);
  for (int g = 0; g < groups; ++g) {
    element_group(m, s, g, beta, iterations, tolerance, nodal, keep_frames, out);
  }
  for (int t = 4 * groups; t < f.tet_count; ++t) {
    const int* ix = f.tets.col(t).data();
    const double* b = f.dm_inv.data() + 9 * t;
    double ds[9], fg[9], g[9], sig[9], p[9];
    edge_matrix(x, ix, ds);
    mul33(ds, b, fg);  // F = Ds Dm^-1
    double* r = s.fem_r.data() + 9 * t;
    double* qd = s.fem_q.data() + 4 * t;
    Eigen::Quaterniond q(qd[0], qd[1], qd[2], qd[3]);
    extract_rotation(fg, q, iterations, tolerance, r);
    qd[0] = q.w();
    qd[1] = q.x();
    qd[2] = q.y();
    qd[3] = q.z();
    mul33_tn(r, fg, g);  // R^T F
    if (beta > 0.0) {
      double dv[9], fd[9], gd[9];
      edge_matrix(v, ix, dv);
      mul33(dv, b, fd);
      mul33_tn(r, fd, gd);
      for (int k = 0; k < 9; ++k) g[k] += beta * gd[k];
    }
    linear_stress(g, mu, lambda, 1.0, sig);
    if (nodal) {
      const double w = 0.25 * f.volume_m3(t) * (g[0] + g[4] + g[8] - 3.0);
      for (int k = 0; k < 4; ++k) s.fem_node_theta[static_cast<std::size_t>(ix[k])] += w;
    }
    mul33(r, sig, p);  // P = R sigma
    scatter_forces(p, b, f.volume_m3(t), ix, 1.0, out);
  }
  if (!nodal) return;
  // the nodes' mean volumetric strains, then each tetrahedron's forces with its pressure
  double* node_theta = s.fem_node_theta.data();
  for (int i = 0; i < f.node_count; ++i) node_theta[i] *= f.inv_node_volume(i);
  for (int g = 0; g < groups; ++g) pressure_group(m, s, g, node_theta, out);
  for (int t = 4 * groups; t < f.tet_count; ++t) {
    const int* ix = f.tets.col(t).data();
    const double pe =
        0.25 * m.lame_lambda_pa *
        (node_theta[ix[0]] + node_theta[ix[1]] + node_theta[ix[2]] + node_theta[ix[3]]);
    double p[9];
    for (int k = 0; k < 9; ++k) p[k] = pe * s.fem_r[9 * static_cast<std::size_t>(t) + k];
    scatter_forces(p, f.dm_inv.data() + 9 * t, f.volume_m3(t), ix, 1.0, out);
  }
}

// out = K p at the current frames (rotate = true) or at rest (false); p and out 3 x N.
TELEOP_HOT_CLONES
void apply_stiffness(const DeformableModel& m, const double* frames, const double* pv,
                     double* theta, double* node_theta, double* out) {
  const DeformableModel::Fem& f = m.fem;
  const bool nodal = m.params.nodal_pressure;
  const double mu = m.lame_mu_pa, lambda = nodal ? 0.0 : m.lame_lambda_pa;
  for (int t = 0; t < f.tet_count; ++t) {
    const int* ix = f.tets.col(t).data();
    const double* b = f.dm_inv.data() + 9 * t;
    double dp[9], df[9], g[9], sig[9], p[9];
    edge_matrix(pv, ix, dp);
    mul33(dp, b, df);
    if (frames != nullptr) {
      const double* r = frames + 9 * t;
      mul33_tn(r, df, g);
      linear_stress(g, mu, lambda, 0.0, sig);
      mul33(r, sig, p);
      scatter_forces(p, b, f.volume_m3(t), ix, -1.0, out);
    } else {
      for (int k = 0; k < 9; ++k) g[k] = df[k];
      linear_stress(df, mu, lambda, 0.0, sig);
      scatter_forces(sig, b, f.volume_m3(t), ix, -1.0, out);
    }
    if (nodal) theta[t] = g[0] + g[4] + g[8];
  }
  if (nodal) nodal_pressure_forces(m, frames, theta, node_theta, -1.0, out);
}

// One node's contact along unit normal n with an obstacle moving at normal speed vo: depth d0
// (> 0 inside) at the start of the step, spring k, damper c, node mass mi. Backward Euler on the
// node: m (vn' - vn) = h (k (d0 - h (vn' - vo)) + c (vo - vn')). Returns the normal impulse
// (>= 0: a contact pushes, never pulls) and updates the node's velocity.
inline double node_contact(const Vec3& n, double d0, double vo, double k, double c, double mi,
                           double h, Vec3& vi) {
  const double vn = n.dot(vi);
  const double vn_new = (mi * vn + h * k * (d0 + h * vo) + h * c * vo) / (mi + h * h * k + h * c);
  const double j = mi * (vn_new - vn);
  if (!(j > 0.0)) return 0.0;
  vi += (vn_new - vn) * n;
  return j;
}

// Coulomb friction of a contact with normal impulse jn: the tangential impulse <= mu jn, never
// more than stops the sliding (relative to an obstacle at rest).
inline void node_friction(const Vec3& n, double jn, double mu, double mi, Vec3& vi) {
  const Vec3 vt = vi - n.dot(vi) * n;
  const double st = vt.norm();
  if (st > 1e-12) vi -= (std::min(mu * jn, mi * st) / (mi * st)) * vt;
}

// Coulomb friction between node i (velocity vi, mass mi) and the tip sphere moving at vo, for a
// contact of normal n and normal impulse jn: the node sticks to the sphere when stopping its
// sliding takes at most mu_s jn, else a tangential impulse mu_k jn opposes the sliding. Returns
// the impulse on the node (the sphere takes its opposite).
inline Vec3 tip_friction(const Vec3& n, double jn, double mu_s, double mu_k, double mi,
                         const Vec3& vo, Vec3& vi) {
  const Vec3 rel = vi - vo;
  const Vec3 vt = rel - n.dot(rel) * n;
  const double st = vt.norm();
  if (!(st > 1e-12) || !(jn > 0.0)) return Vec3::Zero();
  const double stop = mi * st;  // the impulse that stops the sliding
  const double jt = stop <= mu_s * jn ? stop : std::min(mu_k * jn, stop);
  const Vec3 impulse = -(jt / st) * vt;
  vi += impulse / mi;
  return impulse;
}

// The tip sphere's centre at fraction a of the caller's step.
inline Vec3 tip_centre(const DeformableState& s, double a) {
  return s.tip_from_m + a * (s.tip_to_m - s.tip_from_m);
}

// Explicit and symplectic Euler: contacts of the surface nodes as implicit per-node impulses on
// s.v (positions at the start of the step), the tip's reaction into s.tip_force_n (impulse).
void contact_impulses(const DeformableModel& m, DeformableState& s, double h, double tip_alpha) {
  const int ns = m.node_count;
  const DeformableParams& p = m.params;
  const bool tip = s.tip_radius_m > 0.0;
  const Vec3 c = tip ? tip_centre(s, tip_alpha) : Vec3::Zero();
  const double r = s.tip_radius_m, r2 = r * r;
  int touching = 0, plane_contacts = 0;
  double deepest = 0.0;
  for (int i = 0; i < ns; ++i) {
    if (!s.pinned.empty() && s.pinned[static_cast<std::size_t>(i)]) continue;
    const double mi = m.mass_kg(i), k = m.contact_k(i), cd = m.contact_c(i);
    Vec3 vi = s.v.col(i);
    const Vec3 xi = s.x.col(i);
    for (int pl = 0; pl < m.plane_count; ++pl) {
      const Plane& plane = m.planes[static_cast<std::size_t>(pl)];
      const double d0 = plane.offset_m - plane.normal.dot(xi);
      if (d0 <= 0.0) continue;
      const double j = node_contact(plane.normal, d0, 0.0, k, cd, mi, h, vi);
      if (j > 0.0 && p.friction && plane.friction > 0.0) {
        node_friction(plane.normal, j, plane.friction, mi, vi);
      }
      s.plane_force_n += (j / h) * plane.normal;
      ++plane_contacts;
    }
    if (tip) {
      const Vec3 e = xi - c;
      const double e2 = e.squaredNorm();
      if (e2 < r2 && e2 > 0.0) {
        const double dist = std::sqrt(e2);
        const Vec3 n = e / dist;
        const double j = node_contact(n, r - dist, n.dot(s.tip_velocity_mps), k, cd, mi, h, vi);
        const Vec3 jt = tip_friction(n, j, s.tip_friction_static, s.tip_friction_kinetic, mi,
                                     s.tip_velocity_mps, vi);
        s.tip_force_n -= j * n + jt;  // impulse on the tip; step() divides by the step
        ++touching;
        deepest = std::max(deepest, r - dist);
      }
    }
    s.v.col(i) = vi;
  }
  s.contact_count = plane_contacts;
  s.tip_node_count = touching;
  s.tip_depth_m = deepest;
}

// Implicit Euler: the contacts of the surface nodes as springs in the system. Records each one
// (node, normal, (k, c, depth, obstacle normal speed)); the tip's are flagged by a negative
// node index (~i).
void collect_contacts(const DeformableModel& m, DeformableState& s, double tip_alpha) {
  const int ns = m.node_count;
  const bool tip = s.tip_radius_m > 0.0;
  const Vec3 c = tip ? tip_centre(s, tip_alpha) : Vec3::Zero();
  const double r = s.tip_radius_m, r2 = r * r;
  int nc = 0, touching = 0, plane_contacts = 0;
  double deepest = 0.0;
  const int cap = static_cast<int>(s.contact_node.size());
  for (int i = 0; i < ns && nc < cap; ++i) {
    if (!s.pinned.empty() && s.pinned[static_cast<std::size_t>(i)]) continue;
    const Vec3 xi = s.x.col(i);
    for (int pl = 0; pl < m.plane_count && nc < cap; ++pl) {
      const Plane& plane = m.planes[static_cast<std::size_t>(pl)];
      const double d0 = plane.offset_m - plane.normal.dot(xi);
      if (d0 <= 0.0) continue;
      s.contact_node[static_cast<std::size_t>(nc)] = i;
      s.contact_normal.col(nc) = plane.normal;
      s.contact_coef.col(nc) << m.contact_k(i), m.contact_c(i), d0, 0.0;
      ++nc;
      ++plane_contacts;
    }
    if (tip && nc < cap) {
      const Vec3 e = xi - c;
      const double e2 = e.squaredNorm();
      if (e2 < r2 && e2 > 0.0) {
        const double dist = std::sqrt(e2);
        const Vec3 n = e / dist;
        s.contact_node[static_cast<std::size_t>(nc)] = ~i;
        s.contact_normal.col(nc) = n;
        s.contact_coef.col(nc) << m.contact_k(i), m.contact_c(i), r - dist,
            n.dot(s.tip_velocity_mps);
        ++nc;
        ++touching;
        deepest = std::max(deepest, r - dist);
      }
    }
  }
  s.fem_contacts = nc;
  s.contact_count = plane_contacts;
  s.tip_node_count = touching;
  s.tip_depth_m = deepest;
}

// y = A p for A = (1 + h alpha) M + (h beta + h^2) K + sum_contacts (h c + h^2 k) n n^T, held
// nodes' rows and columns replaced by the identity (their dv is fixed at 0).
void apply_system(const DeformableModel& m, DeformableState& s, const Eigen::Matrix3Xd& p,
                  Eigen::Matrix3Xd& y, double h) {
  const DeformableModel::Fem& f = m.fem;
  const int n = f.node_count;
  const double a = 1.0 + h * m.params.mass_damping_per_s;
  const double kk = h * m.params.stiffness_damping_s + h * h;
  y.leftCols(n).setZero();
  apply_stiffness(m, s.fem_r.data(), p.data(), s.fem_theta.data(), s.fem_node_theta.data(),
                  y.data());
  for (int i = 0; i < n; ++i) y.col(i) = a * f.mass_kg(i) * p.col(i) + kk * y.col(i);
  for (int c = 0; c < s.fem_contacts; ++c) {
    const int code = s.contact_node[static_cast<std::size_t>(c)];
    const int i = code >= 0 ? code : ~code;
    const Vec3 nn = s.contact_normal.col(c);
    const double w = h * s.contact_coef(1, c) + h * h * s.contact_coef(0, c);
    y.col(i) += (w * nn.dot(p.col(i))) * nn;
  }
  for (int i = 0; i < n; ++i) {
    if (s.pinned[static_cast<std::size_t>(i)]) y.col(i) = p.col(i);
  }
}

// Implicit Euler: (1 + h alpha) M + (h beta + h^2) K + contacts) dv = h (f - h K v + contact
// forces), K at the current frames, by conjugate_gradient (conjugate_gradient.hpp, the same
// routine as the surface models'); then x += h v.
void implicit_step(const DeformableModel& m, DeformableState& s, double h, double tip_alpha) {
  const DeformableModel::Fem& f = m.fem;
  const int n = f.node_count;
  collect_contacts(m, s, tip_alpha);
  Eigen::Matrix3Xd& b = s.work_b;
  Eigen::Matrix3Xd& ap = s.work_ap;
  ap.leftCols(n).setZero();
  apply_stiffness(m, s.fem_r.data(), s.v.data(), s.fem_theta.data(), s.fem_node_theta.data(),
                  ap.data());  // K v
  b.leftCols(n) = h * (s.work_f.leftCols(n) - h * ap.leftCols(n));
  for (int c = 0; c < s.fem_contacts; ++c) {
    const int code = s.contact_node[static_cast<std::size_t>(c)];
    const int i = code >= 0 ? code : ~code;
    const Vec3 nn = s.contact_normal.col(c);
    const double k = s.contact_coef(0, c), cd = s.contact_coef(1, c), d0 = s.contact_coef(2, c),
                 vo = s.contact_coef(3, c);
    // spring at the step's start plus the obstacle's motion over the step, damper on v
    const double fn = k * (d0 + h * vo) + cd * vo - (h * k + cd) * nn.dot(s.v.col(i));
    b.col(i) += h * fn * nn;
  }
  Eigen::Matrix3Xd& dg = s.work_diag;
  const double a = 1.0 + h * m.params.mass_damping_per_s;
  const double kk = h * m.params.stiffness_damping_s + h * h;
  for (int i = 0; i < n; ++i) {
    dg.col(i) = (a * f.mass_kg(i) + kk * f.precond.col(i).array()).matrix();
  }
  for (int c = 0; c < s.fem_contacts; ++c) {
    const int code = s.contact_node[static_cast<std::size_t>(c)];
    const int i = code >= 0 ? code : ~code;
    const Vec3 nn = s.contact_normal.col(c);
    const double w = h * s.contact_coef(1, c) + h * h * s.contact_coef(0, c);
    dg.col(i) += w * nn.cwiseProduct(nn);
  }
  for (int i = 0; i < n; ++i) {
    if (s.pinned[static_cast<std::size_t>(i)]) {
      b.col(i).setZero();
      dg.col(i).setOnes();
    }
  }
  dg.leftCols(n) = dg.leftCols(n).cwiseInverse();  // stored inverted: the solve multiplies
  conjugate_gradient(m, s, n, [&](const Eigen::Matrix3Xd& p, Eigen::Matrix3Xd& y) {
    apply_system(m, s, p, y, h);
  });
  const Eigen::Matrix3Xd& dv = s.work_dv;
  for (int i = 0; i < n; ++i) {
    if (!s.pinned[static_cast<std::size_t>(i)]) s.v.col(i) += dv.col(i);
  }
  // the contact forces the solve applied (at the new velocities), a contact pushing only
  for (int c = 0; c < s.fem_contacts; ++c) {
    const int code = s.contact_node[static_cast<std::size_t>(c)];
    const int i = code >= 0 ? code : ~code;
    const Vec3 nn = s.contact_normal.col(c);
    const double k = s.contact_coef(0, c), cd = s.contact_coef(1, c), d0 = s.contact_coef(2, c),
                 vo = s.contact_coef(3, c);
    const double vn = nn.dot(s.v.col(i));
    const double fn = std::max(0.0, k * (d0 - h * (vn - vo)) + cd * (vo - vn));
    if (code >= 0) {
      s.plane_force_n += fn * nn;
    } else {
      // friction as an impulse on the solved velocity, from the contact's impulse h fn (held
      // nodes have no contacts)
      Vec3 vi = s.v.col(i);
      const Vec3 jt = tip_friction(nn, h * fn, s.tip_friction_static, s.tip_friction_kinetic,
                                   f.mass_kg(i), s.tip_velocity_mps, vi);
      s.v.col(i) = vi;
      s.tip_force_n -= (h * fn) * nn + jt;
    }
  }
  for (int i = 0; i < n; ++i) s.x.col(i) += h * s.v.col(i);
}

}  // namespace

namespace {

// The rest shape's inverse edge matrices and volumes, per tetrahedron and in groups of four (one
// per lane); returns the body's volume.
double build_rest_geometry(DeformableModel::Fem& f) {
  f.dm_inv.assign(9 * static_cast<std::size_t>(f.tet_count), 0.0);
  f.volume_m3.resize(f.tet_count);
  double volume = 0.0;
  for (int t = 0; t < f.tet_count; ++t) {
    Eigen::Matrix3d dm;
    for (int c = 0; c < 3; ++c) dm.col(c) = f.rest.col(f.tets(c + 1, t)) - f.rest.col(f.tets(0, t));
    const double vol = dm.determinant() / 6.0;
    if (!(vol > 0.0)) bad("tetrahedron " + std::to_string(t) + " has no positive volume");
    f.volume_m3(t) = vol;
    volume += vol;
    Eigen::Map<Eigen::Matrix3d>(f.dm_inv.data() + 9 * t) = dm.inverse();
  }
  const int groups = f.tet_count / 4;
  f.dm_inv4.assign(36 * static_cast<std::size_t>(groups), 0.0);
  f.volume4.assign(4 * static_cast<std::size_t>(groups), 0.0);
  for (int g = 0; g < groups; ++g) {
    for (int l = 0; l < 4; ++l) {
      const std::size_t t = 4 * static_cast<std::size_t>(g) + static_cast<std::size_t>(l);
      for (int k = 0; k < 9; ++k) {
        f.dm_inv4[36 * static_cast<std::size_t>(g) + 4 * static_cast<std::size_t>(k) +
                  static_cast<std::size_t>(l)] = f.dm_inv[9 * t + static_cast<std::size_t>(k)];
      }
      f.volume4[t] = f.volume_m3(static_cast<Eigen::Index>(t));
    }
  }
  return volume;
}

// The material's Lame constants, the body's mass and the lumped node masses (a quarter of each
// tetrahedron's).
void build_masses(DeformableModel& m, double volume) {
  DeformableModel::Fem& f = m.fem;
  const DeformableParams& p = m.params;
  const double E = p.youngs_modulus_pa, nu = p.poisson_ratio;
  m.lame_lambda_pa = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
  m.lame_mu_pa = E / (2.0 * (1.0 + nu));
  m.volume_m3 = volume;
  m.total_mass_kg = p.density_kg_per_m3 > 0.0 ? p.density_kg_per_m3 * volume : p.mass_kg;
  m.density_kg_per_m3 = m.total_mass_kg / volume;
  f.mass_kg = Eigen::VectorXd::Zero(f.node_count);
  for (int t = 0; t < f.tet_count; ++t) {
    for (int k = 0; k < 4; ++k)
      f.mass_kg(f.tets(k, t)) += 0.25 * m.density_kg_per_m3 * f.volume_m3(t);
  }
  f.inv_mass = f.mass_kg.cwiseInverse();
  f.weight_kg = f.mass_kg;
  f.added_mass_kg = 0.0;
  f.inv_node_volume = (f.mass_kg / m.density_kg_per_m3).cwiseInverse();
  m.rest_centre_m = f.rest * f.mass_kg / m.total_mass_kg;
  m.has_centre = false;
  m.centre_mass_kg = 0.0;
  const int ns = m.node_count;
  m.mass_kg = f.mass_kg.head(ns);
  m.inv_mass = f.inv_mass.head(ns);
}

// The surface nodes' areas (a third of each adjacent triangle) and their contact: pressure per
// depth on each node's area, damped at contact_damping_ratio.
void build_surface_contact(DeformableModel& m, double volume) {
  DeformableModel::Fem& f = m.fem;
  const DeformableParams& p = m.params;
  m.area_m2 = Eigen::VectorXd::Zero(m.node_count);
  const auto& X = m.mesh.vertices;
  for (int t = 0; t < m.mesh.triangle_count(); ++t) {
    const int a = m.mesh.triangles(0, t), b = m.mesh.triangles(1, t), c = m.mesh.triangles(2, t);
    const double area = 0.5 * (X.col(b) - X.col(a)).cross(X.col(c) - X.col(a)).norm();
    m.area_m2(a) += area / 3.0;
    m.area_m2(b) += area / 3.0;
    m.area_m2(c) += area / 3.0;
  }
  const double E = p.youngs_modulus_pa, nu = p.poisson_ratio;
  const double size = std::cbrt(volume);
  f.pressure_stiffness_pa_per_m = p.contact_pressure_stiffness_pa_per_m > 0.0
                                      ? p.contact_pressure_stiffness_pa_per_m
                                      : 1000.0 * E / (1.0 - nu * nu) / size;
  m.contact_k = f.pressure_stiffness_pa_per_m * m.area_m2;
  m.contact_c = (2.0 * p.contact_damping_ratio) * (m.contact_k.cwiseProduct(m.mass_kg)).cwiseSqrt();
}

// The diagonal of the rest stiffness: K_jj = V (mu |b_j|^2 I + (lambda + mu) b_j b_j^T).
void build_preconditioner(DeformableModel& m) {
  DeformableModel::Fem& f = m.fem;
  f.precond = Eigen::Matrix3Xd::Zero(3, f.node_count);
  const double mu = m.lame_mu_pa, lambda = m.lame_lambda_pa;
  for (int t = 0; t < f.tet_count; ++t) {
    const Eigen::Map<const Eigen::Matrix3d> b(f.dm_inv.data() + 9 * t);
    Vec3 grad[4];
    for (int j = 0; j < 3; ++j) grad[j + 1] = b.row(j).transpose();
    grad[0] = -(grad[1] + grad[2] + grad[3]);
    for (int k = 0; k < 4; ++k) {
      const Vec3& g = grad[k];
      f.precond.col(f.tets(k, t)) += f.volume_m3(t) * (mu * g.squaredNorm() * Vec3::Ones() +
                                                       (lambda + mu) * g.cwiseProduct(g));
    }
  }
}

}  // namespace

void build_fem(DeformableModel& m, const teleop::mesh::TetMesh& tm) {
  DeformableModel::Fem& f = m.fem;
  f.node_count = tm.node_count();
  f.tet_count = tm.tet_count();
  f.rest = tm.vertices;
  f.tets = tm.tets;
  const double volume = build_rest_geometry(f);
  build_masses(m, volume);
  build_surface_contact(m, volume);
  build_preconditioner(m);
}

void init_fem_state(const DeformableModel& m, DeformableState& s) {
  const DeformableModel::Fem& f = m.fem;
  const int n = f.node_count;
  s.x = f.rest;
  s.v = Eigen::Matrix3Xd::Zero(3, n);
  s.f_ext = Eigen::Matrix3Xd::Zero(3, n);
  s.pinned.assign(static_cast<std::size_t>(n), 0);
  s.pin_target = s.x;
  s.force = Eigen::Matrix3Xd::Zero(3, n);
  for (Eigen::Matrix3Xd* w : {&s.work_f, &s.work_dv, &s.work_r, &s.work_z, &s.work_p, &s.work_ap,
                              &s.work_diag, &s.work_b}) {
    *w = Eigen::Matrix3Xd::Zero(3, n + 1);
  }
  const int cap = m.node_count * (m.plane_count + 1);
  s.contact_node.assign(static_cast<std::size_t>(cap), 0);
  s.contact_normal = Eigen::Matrix3Xd::Zero(3, cap);
  s.contact_coef = Eigen::Matrix4Xd::Zero(4, cap);
  s.fem_q.assign(4 * static_cast<std::size_t>(f.tet_count), 0.0);
  s.fem_r.assign(9 * static_cast<std::size_t>(f.tet_count), 0.0);
  s.fem_theta.assign(static_cast<std::size_t>(f.tet_count), 0.0);
  s.fem_node_theta.assign(static_cast<std::size_t>(f.node_count), 0.0);
  for (int t = 0; t < f.tet_count; ++t) {
    s.fem_q[4 * static_cast<std::size_t>(t)] = 1.0;
    for (int k = 0; k < 3; ++k) s.fem_r[9 * static_cast<std::size_t>(t) + 4 * k] = 1.0;
  }
  s.pin_goal = Eigen::Matrix3Xd::Zero(3, n);
  s.pin_start = Eigen::Matrix3Xd::Zero(3, n);
}

void fem_internal_forces(const DeformableModel& m, DeformableState& s, int rotation_iterations,
                         double rotation_tolerance_rad) {
  const int n = m.fem.node_count;
  s.work_f.leftCols(n).setZero();
  element_forces(m, s, m.params.stiffness_damping_s, rotation_iterations, rotation_tolerance_rad,
                 s.work_f.data());
}

TELEOP_HOT_CLONES
void fem_step(const DeformableModel& m, DeformableState& s, double h, double tip_alpha,
              KernelSums& sums) {
  const DeformableModel::Fem& f = m.fem;
  const DeformableParams& p = m.params;
  const int n = f.node_count;
  Eigen::Matrix3Xd& F = s.work_f;
  // internal forces (elastic + stiffness damping), then gravity, drag and the caller's loads
  F.leftCols(n).setZero();
  element_forces(m, s, p.stiffness_damping_s, kRotationIterations, kRotationTolerance, F.data());
  // alpha damps the velocities relative to the body's support: its own mean velocity while it
  // touches no plane (a falling body keeps g), the planes' frame while it rests on one (its
  // bounce on them is damped too); the plane contacts are those of the last sub-step
  const double alpha = p.mass_damping_per_s;
  Vec3 vmean = Vec3::Zero();
  if (alpha > 0.0 && s.contact_count == 0) {
    for (int i = 0; i < n; ++i) vmean += f.mass_kg(i) * s.v.col(i);
    vmean /= m.total_mass_kg + f.added_mass_kg;
  }
  // gravity on the physical masses, the drag on the inertial ones (they differ by the mass
  // scaling's share)
  for (int i = 0; i < n; ++i) {
    F.col(i) += f.weight_kg(i) * p.gravity_mps2 - (alpha * f.mass_kg(i)) * (s.v.col(i) - vmean) +
                s.f_ext.col(i);
  }
  s.force = F.leftCols(n);
  s.plane_force_n.setZero();
  const auto kind = p.integrator;
  if (kind == IntegratorKind::kImplicitEuler) {
    implicit_step(m, s, h, tip_alpha);
  } else {
    if (kind == IntegratorKind::kExplicitEuler) {
      // positions with the velocities at the start; contacts then act on the new velocities
      for (int i = 0; i < n; ++i) s.x.col(i) += h * s.v.col(i);
    }
    for (int i = 0; i < n; ++i) {
      if (!s.pinned[static_cast<std::size_t>(i)]) s.v.col(i) += (h * f.inv_mass(i)) * F.col(i);
    }
    contact_impulses(m, s, h, tip_alpha);
    if (kind == IntegratorKind::kSymplecticEuler) {
      for (int i = 0; i < n; ++i) s.x.col(i) += h * s.v.col(i);
    }
  }
  // held nodes onto their targets; the sums of the post-step checks
  hold_and_sum(f.weight_kg, n, s, sums);
}

void fem_apply_rest_stiffness(const DeformableModel& m, const Eigen::VectorXd& p,
                              Eigen::VectorXd& y) {
  y.setZero(p.size());
  std::vector<double> theta(static_cast<std::size_t>(m.fem.tet_count)),
      node_theta(static_cast<std::size_t>(m.fem.node_count));
  apply_stiffness(m, nullptr, p.data(), theta.data(), node_theta.data(), y.data());
}

Eigen::VectorXd fem_gershgorin_rows(const DeformableModel& m) {
  const DeformableModel::Fem& f = m.fem;
  const double mu = m.lame_mu_pa, lambda = m.lame_lambda_pa;
  Eigen::VectorXd row = Eigen::VectorXd::Zero(f.node_count);
  for (int t = 0; t < f.tet_count; ++t) {
    const Eigen::Map<const Eigen::Matrix3d> b(f.dm_inv.data() + 9 * t);
    Vec3 grad[4];
    for (int j = 0; j < 3; ++j) grad[j + 1] = b.row(j).transpose();
    grad[0] = -(grad[1] + grad[2] + grad[3]);
    // ||K_ij|| <= V (mu |g_i.g_j| + (lambda + mu) |g_i| |g_j|)
    for (int i = 0; i < 4; ++i) {
      for (int j = 0; j < 4; ++j) {
        row(f.tets(i, t)) += f.volume_m3(t) * (mu * std::fabs(grad[i].dot(grad[j])) +
                                               (lambda + mu) * grad[i].norm() * grad[j].norm());
      }
    }
  }
  return row;
}

double fem_gershgorin_lambda(const DeformableModel& m) {
  return fem_gershgorin_rows(m).cwiseProduct(m.fem.inv_mass).maxCoeff();
}

namespace {

// The inertial masses max(weight_i, row_i / cap) and what depends on them; the stable step
// re-estimated. Returns the mass added [kg].
double set_scaled_masses(DeformableModel& m, const Eigen::VectorXd& row, double cap) {
  DeformableModel::Fem& f = m.fem;
  f.mass_kg = f.weight_kg.cwiseMax(row / cap);
  f.inv_mass = f.mass_kg.cwiseInverse();
  f.added_mass_kg = f.mass_kg.sum() - f.weight_kg.sum();
  const int ns = m.node_count;
  m.mass_kg = f.mass_kg.head(ns);
  m.inv_mass = f.inv_mass.head(ns);
  m.contact_c =
      (2.0 * m.params.contact_damping_ratio) * (m.contact_k.cwiseProduct(m.mass_kg)).cwiseSqrt();
  update_stable_step(m);
  return f.added_mass_kg;
}

}  // namespace

void fem_scale_masses(DeformableModel& m) {
  const DeformableParams& p = m.params;
  const double target = p.mass_scaling_step_s;
  if (!(target > 0.0) || m.stable_step_s >= target) return;
  const Eigen::VectorXd row = fem_gershgorin_rows(m);
  const double allowed = p.mass_scaling_max_fraction * m.total_mass_kg;
  // cap = the largest row / mass ratio left [1/s^2]: hi fails (no scaling), lo passes
  double hi = row.cwiseQuotient(m.fem.weight_kg).maxCoeff(), lo = 0.5 * hi;
  double added = set_scaled_masses(m, row, lo);
  while (m.stable_step_s < target) {
    if (added > allowed || lo < 1e-12 * hi) {
      bad("mass_scaling_step_s " + number_text(target) + " s: the stable step is " +
          number_text(m.stable_step_s) + " s with " + number_text(1e3 * added) + " g added (" +
          number_text(100.0 * added / m.total_mass_kg) +
          " % of the body's mass), and mass_scaling_max_fraction allows " +
          number_text(100.0 * p.mass_scaling_max_fraction) +
          " %: lower mass_scaling_step_s, raise mass_scaling_max_fraction, use a coarser mesh, or "
          "soften what sets the stable step (youngs_modulus_pa " +
          number_text(p.youngs_modulus_pa) + ", poisson_ratio " + number_text(p.poisson_ratio) +
          ", stiffness_damping_s " + number_text(p.stiffness_damping_s) + ", mass_damping_per_s " +
          number_text(p.mass_damping_per_s) + ")");
    }
    hi = lo;
    lo *= 0.5;
    added = set_scaled_masses(m, row, lo);
  }
  // the largest cap that passes, to 2 %
  while (hi / lo > 1.02) {
    const double mid = std::sqrt(lo * hi);
    set_scaled_masses(m, row, mid);
    (m.stable_step_s >= target ? lo : hi) = mid;
  }
  set_scaled_masses(m, row, lo);
}

double fem_elastic_energy(const DeformableModel& m, const DeformableState& s) {
  const DeformableModel::Fem& f = m.fem;
  const bool nodal = m.params.nodal_pressure;
  const double mu = m.lame_mu_pa, lambda = m.lame_lambda_pa;
  double e = 0.0;
  Eigen::VectorXd node_theta = Eigen::VectorXd::Zero(f.node_count);
  for (int t = 0; t < f.tet_count; ++t) {
    const int* ix = f.tets.col(t).data();
    const double* b = f.dm_inv.data() + 9 * t;
    double ds[9], fg[9], g[9];
    edge_matrix(s.x.data(), ix, ds);
    mul33(ds, b, fg);
    const double* q = s.fem_q.data() + 4 * t;
    double r[9];
    quaternion_matrix(q[0], q[1], q[2], q[3], r);
    mul33_tn(r, fg, g);
    double eps[9];
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j)
        eps[3 * j + i] = 0.5 * (g[3 * j + i] + g[3 * i + j]) - (i == j ? 1.0 : 0.0);
    }
    double ee = 0.0;
    for (double x : eps) ee += x * x;
    const double tr = eps[0] + eps[4] + eps[8];
    e += f.volume_m3(t) * mu * ee;
    if (nodal) {
      for (int k = 0; k < 4; ++k) node_theta(ix[k]) += 0.25 * f.volume_m3(t) * tr;
    } else {
      e += f.volume_m3(t) * 0.5 * lambda * tr * tr;
    }
  }
  if (nodal) {
    // sum_a lambda/2 V_a theta_a^2, theta_a = (sum of V_e/4 theta_e) / V_a
    for (int i = 0; i < f.node_count; ++i) {
      e += 0.5 * lambda * node_theta(i) * node_theta(i) * f.inv_node_volume(i);
    }
  }
  return e;
}

}  // namespace teleop::sim::deformable::detail
