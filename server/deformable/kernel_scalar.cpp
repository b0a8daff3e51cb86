// Kernel scalar of the mass-spring symplectic-Euler step (params.kernel == kScalar): the body's
// forces and node update in one pass over the nodes, in double on the state's own 3 x N arrays.
// The same forces and per-node update as the general passes (compute_forces + integrate) and as
// kernel simd (kernel_simd.cpp, which differs in data layout and single-precision forces): the
// spring law of laws/mass_spring.hpp, the plane contact of plane_contact.hpp, then per node
// v += h f / m, the contact impulses, x += h v.
//
// It relies on the edges being sorted by first node (i < j): node i's own edges (i, j) are one
// range, visited with node i; their reactions are added to the later nodes j, whose edges to
// earlier nodes are then complete. So when node i is reached its force is complete, and no later
// edge reads x_i or v_i: node i can be advanced at once. 1 / length of the edges of a block of
// nodes is computed first, in a vectorised loop, while those positions are still the old ones.
// The helpers are always inlined, so each clone keeps its own instruction set. Allocates nothing.
#include <algorithm>
#include <cstdint>

#include "server/deformable/integrators.hpp"
#include "server/deformable/kernels.hpp"
#include "server/deformable/laws/mass_spring.hpp"
#include "server/deformable/plane_contact.hpp"

namespace teleop::sim::deformable::detail {

namespace {

// Nodes per block of the fused mass-spring step (about 100 edges: their data stays in L1).
constexpr int kFusedNodeBlock = 32;

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
    const double fs = spring_tension(k, l2[e], inv_l, l0[e], beta, rate);
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
  const double fs = -spring_tension(kr[i], rl2[i], inv_l, r0[i], rd, rate);
  fx += fs * ux;
  fy += fs * uy;
  fz += fs * uz;
  fc[0] -= fs * ux;
  fc[1] -= fs * uy;
  fc[2] -= fs * uz;
}

}  // namespace

TELEOP_HOT_CLONES
void step_mass_spring_symplectic(const DeformableModel& m, DeformableState& s, double h,
                                 KernelSums& sums) {
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
  Eigen::Vector3d plane_force = Eigen::Vector3d::Zero();
  NodeSums node_sums;

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
      const unsigned touched = node_plane_springs(m, i, xx, xy, xz, spring_of, fx, fy, fz, nc);
      f[a] = fx;
      f[a + 1] = fy;
      f[a + 2] = fz;
      // symplectic Euler: velocity (held nodes keep theirs), contact impulses, position
      symplectic_node(m, i, h, mi, imp[i], any_pinned && pin[i] != 0, tgt + a, xx, xy, xz, vx, vy,
                      vz, fx, fy, fz, touched, spring_of, x, v, plane_force, node_sums);
    }
  }
  s.contact_count = nc;
  s.plane_force_n = plane_force;
  if (centre) symplectic_centre(m, s, h, cv, vm, fc);
  node_sums.store(sums);
}

}  // namespace teleop::sim::deformable::detail
