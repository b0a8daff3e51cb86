#pragma once
// Packing the server's state into its DDS messages: SlaveState every step (echoing the newest
// command's seq and send time so the master measures round trips on its own clock) and mesh
// frames at the visual rate. Allocation-free once the message's sequences have their size.
#include <cstdint>

#include "server/node/server_cycle.hpp"
#include "teleop/idl/Teleop.h"

namespace teleop::server {

/// Who owns the slave, as SlaveState reports it (server/node/ownership.hpp).
struct OwnerReport {
  std::uint32_t session = 0;  ///< current or last owner's master session, 0 = none yet
  bool active = false;        ///< it owns the slave now
  std::uint64_t first_seq = 0;
  std::uint64_t received = 0;  ///< its commands received since it took the slave
};

/// Fills `out` from the cycle's last step. `commands_received`: the reader's count so far;
/// `owner`: the ownership snapshot; `server_time_ns`: the server clock now.
void pack_slave_state(const ServerCycle& cycle, std::uint64_t commands_received,
                      const OwnerReport& owner, std::int64_t server_time_ns, SlaveState& out);

/// Fills `out` with body `index`'s node positions (float32, x y z per node).
void pack_mesh_frame(int object_id, const Eigen::Matrix3Xd& positions_m, std::uint64_t frame_no,
                     double sim_time_s, MeshFrame& out);

}  // namespace teleop::server
