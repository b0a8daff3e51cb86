#pragma once
// SlaveLink: how the master cycle reaches its slave. The cycle hands every command the
// forward delay channel delivers to send(), and asks receive() once per cycle for the newest
// slave sample that arrived. Two transports implement it:
//   - client/node/dds_slave_link: MasterCommand / SlaveState over DDS (teleop_master);
//   - client/sim/loopback_session: an in-process slave stepped after the master half.
// Implementations are called from the haptic loop: they must not allocate or block.
#include "common/control/bilateral_types.hpp"

namespace teleop::master {

class SlaveLink {
 public:
  virtual ~SlaveLink() = default;
  /// Sends one command to the slave (already through the injected forward delay).
  virtual void send(const SlaveCommand& command) = 0;
  /// The newest slave sample that arrived since the last call, if any, with the master-clock
  /// time `at_s` at which it enters the injected backward delay channel [s].
  virtual bool receive(double now_s, SlaveSample& sample, double& at_s) = 0;
};

}  // namespace teleop::master
