#pragma once
// Internal: step kernels of server/deformable/ that live in their own translation units (their
// own compile flags). Not part of the deformable API.
#include "server/deformable/deformable.hpp"

namespace teleop::sim::deformable::detail {

/// What the post-step checks need, gathered while the nodes are advanced.
struct KernelSums {
  double fastest2 = 0.0;           ///< largest squared node speed
  double sum_x = 0.0;              ///< sum of all coordinates (NaN and infinity propagate)
  double sum_v = 0.0;              ///< sum of squared speeds (NaN and infinity propagate)
  double mx[3] = {0.0, 0.0, 0.0};  ///< sum of m_i x_i over the surface nodes
};

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
