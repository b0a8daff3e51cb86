// The node update of the surface models' general passes: explicit, symplectic and (linearly)
// implicit Euler on the forces compute_forces left in s.work_f. The fused kernels
// (kernel_scalar.cpp, kernel_simd.cpp) do the symplectic update of a mass-spring body in their
// own pass; the fem model integrates in fem.cpp. Nothing here allocates.
#include <cstddef>

#include "server/deformable/integrators.hpp"
#include "server/deformable/kernels.hpp"
#include "server/deformable/plane_contact.hpp"

namespace teleop::sim::deformable::detail {

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
  // linearly implicit Euler: the velocity change dv (implicit_solve.cpp), then x += h v
  implicit_velocity_change(m, s, h);
  const Eigen::Matrix3Xd& dv = s.work_dv;
  for (int i = 0; i < n; ++i) {
    if (!s.pinned[static_cast<std::size_t>(i)]) s.v.col(i) += dv.col(i);
    s.x.col(i) += h * s.v.col(i);
  }
  if (m.has_centre) {
    s.centre_v += dv.col(n);
    s.centre_x += h * s.centre_v;
  }
}

}  // namespace teleop::sim::deformable::detail
