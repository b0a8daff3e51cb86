#include "server/node/command_gate.hpp"

namespace teleop::server {

CommandGate::CommandGate(const Eigen::Vector3d& workspace_min_m,
                         const Eigen::Vector3d& workspace_max_m, std::int64_t owner_timeout_ns)
    : workspace_min_m_(workspace_min_m),
      workspace_max_m_(workspace_max_m),
      ownership_(owner_timeout_ns) {}

bool CommandGate::pass(const MasterCommand& cmd, const WriterId& writer, std::int64_t now_ns) {
  ++counts_.received;
  admit_ = Admit::kIgnored;
  // 1. fields (the sequence is the owner's, checked after ownership)
  verdict_ = validate_command(cmd, workspace_min_m_, workspace_max_m_, 0, false);
  // 2. ownership
  if (verdict_ == CommandVerdict::kAccepted) {
    admit_ = ownership_.admit(writer, cmd.master_session(), cmd.master_name().c_str(), cmd.seq(),
                              cmd.release(), now_ns);
    switch (admit_) {
      case Admit::kRefused:
        ++counts_.refused_owner;
        return false;
      case Admit::kReleased:
        ++counts_.releases;
        return false;
      case Admit::kIgnored:
        return false;
      case Admit::kAcquired:
      case Admit::kTakenOver:
        // a new owner numbers its commands and its passivity session from its own start
        have_last_ = false;
        passivity_ = PassivityHistory{};
        break;
      case Admit::kOwner:
        break;
    }
    // 3. the owner's sequence and passivity fields
    if (have_last_ && cmd.seq() <= last_seq_) verdict_ = CommandVerdict::kStale;
    if (verdict_ == CommandVerdict::kAccepted) verdict_ = validate_passivity(cmd, passivity_);
  }
  switch (verdict_) {
    case CommandVerdict::kAccepted:
      have_last_ = true;
      last_seq_ = cmd.seq();
      ++counts_.accepted;
      return true;
    case CommandVerdict::kOutsideWorkspace:
      ++counts_.rejected_workspace;
      return false;
    case CommandVerdict::kStale:
      ++counts_.rejected_stale;
      return false;
    case CommandVerdict::kBadPassivity:
      ++counts_.rejected_passivity;
      return false;
    default:
      ++counts_.rejected_nan;
      return false;
  }
}

}  // namespace teleop::server
