// The forces on the nodes of a surface model (mass_spring, navier_linear, navier_corotational):
// gravity, drag and the caller's loads, the model's internal force law (laws/), the radial
// springs to the centre node and the plane contacts (plane_contact.hpp), summed per node. Nothing
// here allocates: every buffer lives in DeformableState and was sized by make_state().
#include <cmath>
#include <cstddef>

#include "server/deformable/fem.hpp"
#include "server/deformable/kernels.hpp"
#include "server/deformable/laws/mass_spring.hpp"
#include "server/deformable/laws/navier_corotational.hpp"
#include "server/deformable/laws/navier_linear.hpp"
#include "server/deformable/plane_contact.hpp"

namespace teleop::sim::deformable {

namespace detail {

// A loop the compiler vectorises (-fno-math-errno; a max() would stop it).
TELEOP_HOT_CLONES __attribute__((optimize("O3"))) void inverse_sqrt(const double* __restrict in,
                                                                    double* __restrict out,
                                                                    int count) {
  for (int k = 0; k < count; ++k) out[k] = 1.0 / std::sqrt(in[k] + 1e-30);
}

namespace {

// Gravity, drag and the caller's loads into s.work_f (every node; column N too if there is a
// centre node). The drag is relative to the mean velocity: it damps deformation, keeps momentum.
TELEOP_ALWAYS_INLINE void set_external_forces(const DeformableModel& m, DeformableState& s) {
  const int n = m.node_count;
  const DeformableParams& p = m.params;
  Eigen::Matrix3Xd& F = s.work_f;
  const Eigen::Matrix3Xd& v = s.v;
  const double alpha = p.mass_damping_per_s;
  Eigen::Vector3d vcm = Eigen::Vector3d::Zero();
  if (alpha > 0.0) vcm = (v * m.mass_kg + m.centre_mass_kg * s.centre_v) / m.total_mass_kg;
  for (int i = 0; i < n; ++i) {
    F.col(i) = m.mass_kg(i) * (p.gravity_mps2 - alpha * (v.col(i) - vcm)) + s.f_ext.col(i);
  }
  if (m.has_centre) F.col(n) = m.centre_mass_kg * (p.gravity_mps2 - alpha * (s.centre_v - vcm));
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

}  // namespace

// The laws' helpers are always inlined, so each instruction-set clone has its own copy.
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

}  // namespace detail

void internal_forces(const DeformableModel& m, DeformableState& s, Eigen::Matrix3Xd& out) {
  if (m.params.model == ModelKind::kFem) {
    detail::fem_internal_forces(m, s, 200, 1e-13);
    if (out.cols() != m.fem.node_count) out.resize(3, m.fem.node_count);
    out = s.work_f.leftCols(m.fem.node_count);
    return;
  }
  detail::ForceFlags flags;
  flags.external = false;
  flags.contact = false;
  flags.rotation_iterations = 200;
  flags.rotation_tolerance_rad = 1e-13;
  detail::compute_forces(m, s, 1.0, flags);
  if (out.cols() != m.node_count) out.resize(3, m.node_count);
  out = s.work_f.leftCols(m.node_count);
}

}  // namespace teleop::sim::deformable
