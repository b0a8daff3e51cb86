#include "server/node/state_message.hpp"

#include "common/dds/teleop_idl.hpp"
#include "server/node/slave_sample.hpp"

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
  // what the master reads, as the in-process slave hands it over (server/node/slave_sample.hpp)
  SlaveSample sample;
  slave_sample(cycle, sample);
  to_idl(sample, cycle.have_command() ? cycle.command_send_time_ns() : 0, state);
  // and what only the wire carries
  const sim::WorldOutput& out = cycle.output();
  state.server_time_ns(server_time_ns);
  const auto nj = static_cast<std::size_t>(out.joint_count);
  state.joint_position_rad().resize(nj);
  state.joint_velocity_radps().resize(nj);
  state.joint_torque_nm().resize(nj);
  for (std::size_t j = 0; j < nj; ++j) {
    state.joint_position_rad()[j] = out.q_rad[j];
    state.joint_velocity_radps()[j] = out.qd_radps[j];
    state.joint_torque_nm()[j] = out.tau_nm[j];
  }
  copy3(state.tip_angular_velocity_radps(), out.tip_angular_velocity_radps);
  copy3(state.contact_torque_nm(), out.contact_torque_nm);
  state.contact_object(out.contact_object);
  state.holding(cycle.held());
  state.step_time_us(static_cast<float>(cycle.step_time_us()));
  state.commands_received(commands_received);
  state.owner_session(owner.session);
  state.owner_active(owner.active);
  state.owner_first_seq(owner.first_seq);
  state.owner_commands_received(owner.received);
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
