#pragma once
// The slave half of an in-process session (client/sim/loopback_session.hpp): what the master
// cycle's in-process link steps once per cycle. The one implementation is the server's own
// physics period without DDS (server/node/world_slave.hpp: ServerCycle, that is watchdog,
// passivity port and world_step), so an in-process run and a networked one step the same
// world. The interface lives here so the client's harness does not depend on the server.
#include <Eigen/Core>

#include "common/control/bilateral_types.hpp"

namespace teleop {

/// A slave simulated in-process.
class SlaveSimulator {
 public:
  virtual ~SlaveSimulator() = default;
  /// Puts the tool at rest at `position_m` [m], time zero (allocation allowed).
  virtual void reset(const Eigen::Vector3d& position_m) = 0;
  /// Advances by dt [s] towards `command`, the newest command the slave has (a command whose
  /// seq and send time are those of the last step is not a new arrival). Allocation-free.
  virtual void step(const SlaveCommand& command, double dt_s) = 0;
  /// The state to send back to the master (what the server packs into SlaveState).
  virtual const SlaveSample& sample() const = 0;
};

}  // namespace teleop
