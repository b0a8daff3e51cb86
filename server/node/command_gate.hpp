#pragma once
// The server's edge for MasterCommand samples, the same for the live node (its command reader
// thread) and the off-line re-simulation (resim.cpp), in this order:
//   1. field checks (validate_command without the sequence): NaN / Inf, absurd magnitudes, the
//      quaternion, the workspace, the gain. A malformed command can neither take nor keep the
//      slave;
//   2. ownership (ownership.hpp): commands of a master that does not own the slave are refused;
//      a release ends the owner's session; a new owner restarts the sequence numbering and the
//      passivity history;
//   3. the owner's sequence (older or repeated seq: stale) and passivity fields.
// Only commands that pass all three reach the physics. Every outcome is counted. Allocation-free;
// not thread-safe (one caller thread).
#include <cstdint>

#include "server/node/command_validation.hpp"
#include "server/node/ownership.hpp"
#include "teleop/idl/Teleop.h"

namespace teleop::server {

/// Counts of the gate's outcomes since it was made.
struct GateCounts {
  std::uint64_t received = 0;
  std::uint64_t accepted = 0;
  std::uint64_t rejected_nan = 0;  ///< non-finite or absurd fields, bad quaternion or gain
  std::uint64_t rejected_workspace = 0;
  std::uint64_t rejected_stale = 0;
  std::uint64_t rejected_passivity = 0;
  std::uint64_t refused_owner = 0;  ///< from a master that did not own the slave
  std::uint64_t releases = 0;       ///< the owner gave the slave up
};

class CommandGate {
 public:
  /// `owner_timeout_ns`: the ownership watchdog (Ownership).
  CommandGate(const Eigen::Vector3d& workspace_min_m, const Eigen::Vector3d& workspace_max_m,
              std::int64_t owner_timeout_ns);

  /// One command from `writer` received at `now_ns`. Returns true if it goes to the physics.
  /// `verdict` says why not (kAccepted for refusals and releases, see `admit()`).
  bool pass(const MasterCommand& cmd, const WriterId& writer, std::int64_t now_ns);

  /// The last pass()'s field / sequence / passivity verdict and ownership decision.
  CommandVerdict verdict() const { return verdict_; }
  Admit admit() const { return admit_; }
  const Ownership& ownership() const { return ownership_; }
  const GateCounts& counts() const { return counts_; }
  std::uint64_t rejected() const {
    return counts_.rejected_nan + counts_.rejected_workspace + counts_.rejected_stale +
           counts_.rejected_passivity;
  }

 private:
  Eigen::Vector3d workspace_min_m_, workspace_max_m_;
  Ownership ownership_;
  bool have_last_ = false;
  std::uint64_t last_seq_ = 0;
  PassivityHistory passivity_;
  GateCounts counts_;
  CommandVerdict verdict_ = CommandVerdict::kAccepted;
  Admit admit_ = Admit::kIgnored;
};

}  // namespace teleop::server
