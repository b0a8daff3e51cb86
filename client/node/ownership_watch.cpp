#include "client/node/ownership_watch.hpp"

namespace teleop::master {

OwnershipWatch::Change OwnershipWatch::update(DdsSlaveLink::Owner owner, double now_s) {
  if (owner == DdsSlaveLink::Owner::kMine) {
    owned_once_ = true;
    if (!refused_) return Change::kNone;
    refused_ = false;
    last_wait_s_ = now_s - refused_at_s_;
    waited_s_ += last_wait_s_;
    return Change::kGotSlave;
  }
  if (owner != DdsSlaveLink::Owner::kOther) return Change::kNone;
  // another owner before this master's first answer could come back is not a refusal yet
  if (!refused_ && (owned_once_ || now_s - t0_s_ > grace_s_)) {
    refused_ = true;
    refused_first_ = !owned_once_;
    refused_at_s_ = now_s;
    if (wait_owner_s_ <= 0) give_up_ = true;
    return Change::kRefused;
  }
  if (refused_ && now_s - refused_at_s_ > wait_owner_s_) give_up_ = true;
  return Change::kNone;
}

}  // namespace teleop::master
