#pragma once
// Internal: the co-rotational Navier law (model navier_corotational) of server/deformable/: the
// linear-strain law of laws/navier_linear.hpp applied in a frame that turns with the body. Each
// node's frame is the rotation of its one-ring (rotation.hpp's polar decomposition, warm-started
// from the last step); an edge uses the mean of its two nodes' frames R and the force on its
// first node is
//   f = R (a g + b (g . u0) u0),  g = R^T ((x_j - x_i) + beta (v_j - v_i)) - (X_j - X_i).
// Two forms: navier_corotational_edge_forces for implicit Euler (with the implicit blocks) and
// the four-lane path (pack_corotational, corotational_frames, corotational_edges) for the
// explicit and symplectic steps. Not part of the deformable API.
#include <algorithm>
#include <cstddef>

#include "server/deformable/kernels.hpp"
#include "server/deformable/rotation.hpp"

namespace teleop::sim::deformable::detail {

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
    const Eigen::Matrix3d r =
        0.5 * (s.rotation[static_cast<std::size_t>(i)] + s.rotation[static_cast<std::size_t>(j)]);
    const Eigen::Vector3d u0 = m.rest_dir.col(e);
    // hand-written 3x3 products (Eigen does not inline these mixed expressions here)
    const Eigen::Vector3d q = (x.col(j) - x.col(i)) + beta * (v.col(j) - v.col(i));
    const Eigen::Vector3d g =
        Eigen::Vector3d(r.col(0).dot(q), r.col(1).dot(q), r.col(2).dot(q)) - (X.col(j) - X.col(i));
    const double a = m.edge_k_iso(e), b = m.edge_k_dir(e);
    const Eigen::Vector3d loc = a * g + (b * g.dot(u0)) * u0;
    const Eigen::Vector3d f = r.col(0) * loc.x() + r.col(1) * loc.y() + r.col(2) * loc.z();
    s.edge_force.col(e) = f;
    s.edge_dir.col(e) = (r * u0).normalized();
    s.edge_coef.col(e) << a, b, beta * a, beta * b;
  }
}
// --- co-rotational Navier, explicit and symplectic path ---------------------------------------
// Four doubles at a time with GCC's vector extensions: 3-vectors padded to 4 lanes (AVX2 in the
// x86-64-v3 clone, two SSE2 halves in the default one). Per node, the positions relative to the
// centroid and the damped positions x - c + beta v are packed (4 + 4 doubles), the ring matrix is
// built column by column from the model's rest tables, and its rotation is extracted
// (warm-started; four nodes in lanes where one Newton step settles them, else one by one); the
// frame is stored as columns and rows. Per edge, R = (R_i + R_j) / 2
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
  const V4 t0 = __builtin_shufflevector(a, b, 0, 4, 1, 5);
  const V4 t1 = __builtin_shufflevector(a, b, 2, 6, 3, 7);
  const V4 t2 = __builtin_shufflevector(c, d, 0, 4, 1, 5);
  const V4 t3 = __builtin_shufflevector(c, d, 2, 6, 3, 7);
  a = __builtin_shufflevector(t0, t2, 0, 1, 4, 5);
  b = __builtin_shufflevector(t0, t2, 2, 3, 6, 7);
  c = __builtin_shufflevector(t1, t3, 0, 1, 4, 5);
  d = __builtin_shufflevector(t1, t3, 2, 3, 6, 7);
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
// 1 / |D|^2: 4 doubles per edge). Node by node over the edges whose first node it is (the edges
// are sorted by
// first node, i < j): node i's pack and frame stay in registers, the force is summed for i and
// its reaction subtracted from j's accumulator (acc, 4 doubles per node, zero before node 0).
// When node i is reached every edge where it is the second node has been counted: the return
// value is node i's complete edge force (x, y, z, 0).
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

}  // namespace teleop::sim::deformable::detail
