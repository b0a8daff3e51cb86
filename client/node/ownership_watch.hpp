#pragma once
// How the master reacts to the server's ownership decisions during a run (docs/topics.md,
// "Ownership"): a master refused the slave holds (renders nothing, commands nothing) and ends the
// session unless it waits for the slave; one that gets the slave after waiting re-homes. The
// watch decides; the node carries the decision out on the cycle and publishes the event.
#include <cstdint>

#include "client/node/dds_slave_link.hpp"

namespace teleop::master {

class OwnershipWatch {
 public:
  /// What one update asks of the node.
  enum class Change : std::uint8_t {
    kNone = 0,     ///< nothing new
    kRefused = 1,  ///< another master owns the slave: hold the cycle, publish the refusal
    kGotSlave = 2  ///< the slave is this master's after waiting: release the hold, re-home
  };

  /// `t0_s`: the loop's start [s]; `grace_s`: how long this master's first commands may take to
  /// reach the server and its answer to come back, during which another owner is not yet a
  /// refusal [s]; `wait_owner_s`: how long a refused master waits for the slave (<= 0: it gives
  /// up at once) [s].
  OwnershipWatch(double t0_s, double grace_s, double wait_owner_s)
      : t0_s_(t0_s), grace_s_(grace_s), wait_owner_s_(wait_owner_s) {}

  /// Once per cycle, with the ownership the newest SlaveState reports at `now_s` [s].
  Change update(DdsSlaveLink::Owner owner, double now_s);

  /// Refused and still waiting: the cycle holds.
  bool refused() const { return refused_; }
  /// Refused and not (or no longer) waiting: the session ends.
  bool give_up() const { return give_up_; }
  /// The newest refusal came before this master ever owned the slave.
  bool refused_first() const { return refused_first_; }
  /// How long the wait that kGotSlave ended took [s].
  double last_wait_s() const { return last_wait_s_; }
  /// Time spent refused up to `end_s`, the refusal still running included [s].
  double waited_s(double end_s) const {
    return waited_s_ + (refused_ ? end_s - refused_at_s_ : 0.0);
  }
  /// The wait a refusal allows [s] (<= 0: none).
  double wait_owner_s() const { return wait_owner_s_; }

 private:
  double t0_s_;
  double grace_s_;
  double wait_owner_s_;
  bool refused_ = false;
  /// This master has owned the slave since its teleoperation session began.
  bool owned_once_ = false;
  bool give_up_ = false;
  bool refused_first_ = false;
  double refused_at_s_ = 0.0;
  double waited_s_ = 0.0;  // the ended waits [s]
  double last_wait_s_ = 0.0;
};

}  // namespace teleop::master
