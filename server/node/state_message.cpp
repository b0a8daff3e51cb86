#include "server/node/state_message.hpp"

#include "common/dds/teleop_idl.hpp"

namespace teleop::server {

namespace {
void copy3(std::array<double, 3>& dst, const Eigen::Vector3d& v) {
  dst[0] = v.x();
  dst[1] = v.y();
  dst[2] = v.z();
}
}  // namespace

void pack_slave_state(const ServerCycle& cycle, std::uint64_t commands_received,
                      const OwnerReport& owner, std::int64_t server_time_ns, SlaveState& state) {
  const sim::WorldOutput& out = cycle.output();
  state.seq(cycle.steps());
  if (cycle.have_command()) {
    state.command_seq(cycle.command().seq);
    state.command_send_time_ns(cycle.command_send_time_ns());
  }
  state.server_time_ns(server_time_ns);
  state.sim_time_s(out.sim_time_s);
  const auto nj = static_cast<std::size_t>(out.joint_count);
  state.joint_position_rad().resize(nj);
  state.joint_velocity_radps().resize(nj);
  state.joint_torque_nm().resize(nj);
  for (std::size_t j = 0; j < nj; ++j) {
    state.joint_position_rad()[j] = out.q_rad[j];
    state.joint_velocity_radps()[j] = out.qd_radps[j];
    state.joint_torque_nm()[j] = out.tau_nm[j];
  }
  copy3(state.tip_position_m(), out.tip_position_m);
  state.tip_orientation_wxyz() = {out.tip_orientation.w(), out.tip_orientation.x(),
                                  out.tip_orientation.y(), out.tip_orientation.z()};
  copy3(state.tip_linear_velocity_mps(), out.tip_velocity_mps);
  copy3(state.tip_angular_velocity_radps(), out.tip_angular_velocity_radps);
  copy3(state.contact_force_n(), out.contact_force_n);
  copy3(state.contact_torque_nm(), out.contact_torque_nm);
  state.penetration_m(out.penetration_m);
  state.deformation_m(out.deformation_m);
  state.in_contact(out.in_contact);
  state.contact_object(out.contact_object);
  state.holding(cycle.held());
  state.step_time_us(static_cast<float>(cycle.step_time_us()));
  state.commands_received(commands_received);
  const passivity::SlavePortReport& pr = cycle.port().report();
  state.passivity_session(cycle.port_active() ? pr.session : 0);
  for_each_port([&state](const auto& p) { to_wire(p, state); }, pr);
  state.passivity_dissipated_j(pr.dissipated_j);
  state.owner_session(owner.session);
  state.owner_active(owner.active);
  state.owner_first_seq(owner.first_seq);
  state.owner_commands_received(owner.received);
  to_idl(cycle.local_model(), state);
}

void pack_mesh_frame(int object_id, const Eigen::Matrix3Xd& x, std::uint64_t frame_no,
                     double sim_time_s, MeshFrame& frame) {
  frame.object_id(object_id);
  frame.frame(frame_no);
  frame.sim_time_s(sim_time_s);
  auto& pos = frame.positions_m();
  pos.resize(static_cast<std::size_t>(x.size()));
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    pos[static_cast<std::size_t>(k)] = static_cast<float>(x.data()[k]);
  }
}

}  // namespace teleop::server
