#pragma once
// The server's output as the master reads it: one conversion from a ServerCycle's last step to
// a SlaveSample. The in-process slave (server/node/world_slave.hpp) hands this sample to the
// master's loop directly; teleop_server writes the same sample as SlaveState (to_idl in
// common/dds/teleop_idl.hpp, server/node/state_message.cpp) and the master reads it back with
// from_idl, its inverse. Allocation-free.
#include "common/control/bilateral_types.hpp"
#include "server/node/server_cycle.hpp"

namespace teleop::server {

/// Copies the tip's state after a world step into `s`: position, orientation, velocity, contact
/// force, penetration, deformation, in_contact and the simulated time (the other fields of `s`
/// are left as they are).
inline void copy_tip_state(const sim::WorldOutput& o, SlaveSample& s) {
  s.position_m = o.tip_position_m;
  s.orientation = o.tip_orientation;
  s.velocity_mps = o.tip_velocity_mps;
  s.contact_force_n = o.contact_force_n;
  s.penetration_m = o.penetration_m;
  s.deformation_m = o.deformation_m;
  s.in_contact = o.in_contact;
  s.sim_time_s = o.sim_time_s;
}

/// Fills `s` from the cycle's last step: the tip's state, the step count, the echo of the newest
/// command (its seq and send time; 0 before the first), the passivity port's report (session 0
/// while no port is active) and the local contact model; valid. slave_epoch is the transport's
/// and is left as it is.
void slave_sample(const ServerCycle& cycle, SlaveSample& s);

}  // namespace teleop::server
