// world_prewarm (server/world/world.hpp).
#include <algorithm>

#include "common/util/prewarm.hpp"
#include "server/world/world.hpp"

namespace teleop::sim {
namespace {

using deformable::DeformableModel;
using deformable::DeformableState;
using deformable::IntegratorKind;

/// The per-edge and per-node arrays of the force pass and the integrator.
std::uint64_t touch_model(const DeformableModel& m) {
  std::uint64_t s = touch(m.mass_kg) + touch(m.inv_mass) + touch(m.area_m2) + touch(m.edges) +
                    touch(m.rest_length_m) + touch(m.rest_dir) + touch(m.edge_k_iso) +
                    touch(m.edge_k_dir) + touch(m.node_edge_offsets) + touch(m.node_edges) +
                    touch(m.first_edge_offsets) + touch(m.second_node3) + touch(m.radial_k) +
                    touch(m.radial_rest_m) + touch(m.contact_k) + touch(m.contact_c);
  s += touch(m.simd_neighbour) + touch(m.simd_k) + touch(m.simd_rest) + touch(m.simd_radial_k) +
       touch(m.simd_radial_rest) + touch(m.simd_dof_mass) + touch(m.simd_dof_inv_mass);
  s += touch(m.corot_nb) + touch(m.corot_ring_rest) + touch(m.corot_node_e) + touch(m.corot_edge) +
       touch(m.corot_ring_rest4) + touch(m.corot_node_e4);
  const DeformableModel::Fem& f = m.fem;
  s += touch(f.rest) + touch(f.tets) + touch(f.dm_inv) + touch(f.dm_inv4) + touch(f.volume4) +
       touch(f.volume_m3) + touch(f.mass_kg) + touch(f.inv_mass) + touch(f.weight_kg) +
       touch(f.inv_node_volume);
  if (m.params.integrator == IntegratorKind::kImplicitEuler) s += touch(f.precond);
  return s;
}

std::uint64_t touch_state(const DeformableModel& m, const DeformableState& st) {
  std::uint64_t s = touch(st.x) + touch(st.v) + touch(st.f_ext) + touch(st.pinned) +
                    touch(st.pin_target) + touch(st.force) + touch(st.work_f) +
                    touch(st.edge_scratch) + touch(st.edge_length2) + touch(st.node_length2) +
                    touch(st.edge_force) + touch(st.node_scratch) + touch(st.simd_pack);
  s += touch(st.rotation) + touch(st.rotation_q) + touch(st.corot_pack) + touch(st.corot_frame) +
       touch(st.corot_force) + touch(st.fem_q) + touch(st.fem_r) + touch(st.fem_theta) +
       touch(st.fem_node_theta);
  if (m.params.integrator == IntegratorKind::kImplicitEuler) {
    s += touch(st.work_dv) + touch(st.work_r) + touch(st.work_z) + touch(st.work_p) +
         touch(st.work_ap) + touch(st.work_diag) + touch(st.work_b) + touch(st.edge_dir) +
         touch(st.edge_coef) + touch(st.radial_dir) + touch(st.radial_coef) +
         touch(st.contact_node) + touch(st.contact_normal) + touch(st.contact_coef);
  }
  return s;
}

}  // namespace

std::uint64_t world_prewarm(const WorldModel& model, const WorldData& data) {
  std::uint64_t s = 0;
  const std::size_t n = std::min(model.bodies.size(), data.bodies.size());
  for (std::size_t i = 0; i < n; ++i) {
    const DeformableModel& m = model.bodies[i].body;
    const DeformableBodyData& b = data.bodies[i];
    s += b.contact.touch();
    // a sleeping body's step reads only its flags; the tip's contact query still reads the tree
    if (b.state.sleeping) continue;
    s += touch_model(m) + touch_state(m, b.state);
  }
  return s;
}

}  // namespace teleop::sim
