#pragma once
// Internal: the passes of the deformable step (server/deformable/) and what they exchange. Not
// part of the deformable API. step.cpp dispatches a step to one of them:
//   - the general passes of the surface models: compute_forces (forces.cpp, with the laws of
//     laws/ and plane_contact.hpp), then integrate (integrators.hpp; implicit Euler solves with
//     implicit_solve.cpp);
//   - the fused mass-spring symplectic-Euler kernels: scalar (kernel_scalar.cpp) and simd
//     (kernel_simd.cpp), the same law and node update in two data layouts;
//   - the volumetric FEM (fem.cpp).
#include "server/deformable/deformable.hpp"
#include "server/deformable/hot.hpp"

namespace teleop::sim::deformable::detail {

/// What the post-step checks need, gathered while the nodes are advanced.
struct KernelSums {
  double fastest2 = 0.0;           ///< largest squared node speed
  double sum_x = 0.0;              ///< sum of all coordinates (NaN and infinity propagate)
  double sum_v = 0.0;              ///< sum of squared speeds (NaN and infinity propagate)
  double mx[3] = {0.0, 0.0, 0.0};  ///< sum of m_i x_i over the surface nodes
};

/// What compute_forces adds.
struct ForceFlags {
  bool external = true;         ///< gravity, drag, f_ext
  bool contact = true;          ///< plane penalties and friction
  bool jacobian = false;        ///< fill the blocks for the implicit solve
  int rotation_iterations = 8;  ///< co-rotational: polar-decomposition iterations per node (max)
  double rotation_tolerance_rad = 1e-7;  ///< co-rotational: stop when the increment is smaller
};

/// Total force on every node of a surface model (and on the centre node, column N) into
/// s.work_f at (s.x, s.v) [N]; with flags.jacobian also the stiffness and damping blocks of the
/// implicit solve. Records the plane contacts. Allocates nothing.
void compute_forces(const DeformableModel& m, DeformableState& s, double h, ForceFlags flags);

/// Implicit Euler of a surface model: the velocity change dv of (M + h C + h^2 K) dv =
/// h (f - h K v) into s.work_dv (column N: the centre node), with the blocks compute_forces
/// stored (flags.jacobian) and f in s.work_f; held nodes get dv = 0. Allocates nothing.
void implicit_velocity_change(const DeformableModel& m, DeformableState& s, double h);

/// Kernel scalar (params.kernel == kScalar): one symplectic-Euler step of a mass-spring body in
/// one pass over the nodes (kernel_scalar.cpp). Pinned-node velocities must already be set.
/// Allocates nothing.
void step_mass_spring_symplectic(const DeformableModel& m, DeformableState& s, double h,
                                 KernelSums& sums);

/// Kernel simd (params.kernel == kSimd): one symplectic-Euler step of a mass-spring body.
/// The same forces and per-node update as the scalar kernel; the edge and radial forces are
/// evaluated in single precision on structure-of-arrays copies (positions relative to the centre
/// node), vectorised over nodes, and the integration is in double. Pinned-node velocities must
/// already be set (step_impl does). `loads_zero`: every f_ext entry is zero (scan_loads), so
/// the kernel need not read them. `pack_next`: another sub-step of this step() call follows, so
/// the position pass also writes the next sub-step's pack (s.simd_pack_fresh: that sub-step
/// skips its pack pass; the same bits as packing again). Allocates nothing.
void step_mass_spring_simd(const DeformableModel& m, DeformableState& s, double h, bool loads_zero,
                           bool pack_next, KernelSums& sums);

}  // namespace teleop::sim::deformable::detail
