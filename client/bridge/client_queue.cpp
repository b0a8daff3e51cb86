#include "client/bridge/client_queue.hpp"

namespace teleop::bridge {

ClientQueue::ClientQueue(std::size_t bound_bytes, std::size_t bulk_channels, std::size_t kept_slots)
    : bound_(bound_bytes),
      kept_(kept_slots < 1 ? 1 : kept_slots),
      bulk_(bulk_channels),
      bulk_full_(bulk_channels, false) {}

void ClientQueue::emptied(std::vector<std::uint8_t>& slot) {
  if (retained_ <= 2 * bound_) return;
  retained_ -= slot.capacity();
  std::vector<std::uint8_t>().swap(slot);
}

bool ClientQueue::drop_one_bulk() {
  for (std::size_t i = 0; i < bulk_.size(); ++i) {
    if (!bulk_full_[i]) continue;
    bytes_ -= bulk_[i].size();
    bulk_full_[i] = false;
    --bulk_waiting_;
    ++counts_.dropped_bulk;
    emptied(bulk_[i]);
    return true;
  }
  return false;
}

void ClientQueue::drop_oldest_kept() {
  bytes_ -= kept_[kept_head_].size();
  emptied(kept_[kept_head_]);
  kept_head_ = (kept_head_ + 1) % kept_.size();
  --kept_count_;
  ++counts_.dropped_kept;
}

void ClientQueue::push(FrameClass cls, std::size_t bulk_channel, std::span<const std::uint8_t> head,
                       std::span<const std::uint8_t> body) {
  const std::size_t n = head.size() + body.size();
  if (n > bound_ || (cls == FrameClass::kBulk && bulk_channel >= bulk_.size())) {
    ++counts_.too_large;
    return;
  }
  std::vector<std::uint8_t>* slot = nullptr;
  if (cls == FrameClass::kBulk) {
    if (bulk_full_[bulk_channel]) {
      // a newer frame of the same channel replaces the waiting one
      bytes_ -= bulk_[bulk_channel].size();
      bulk_full_[bulk_channel] = false;
      --bulk_waiting_;
      ++counts_.dropped_bulk;
    }
    while (bytes_ + n > bound_ && drop_one_bulk()) {
    }
    while (bytes_ + n > bound_ && kept_count_ > 0) drop_oldest_kept();
    slot = &bulk_[bulk_channel];
    bulk_full_[bulk_channel] = true;
    ++bulk_waiting_;
  } else {
    while (bytes_ + n > bound_ && drop_one_bulk()) {
    }
    while ((bytes_ + n > bound_ || kept_count_ == kept_.size()) && kept_count_ > 0) {
      drop_oldest_kept();
    }
    slot = &kept_[(kept_head_ + kept_count_) % kept_.size()];
    ++kept_count_;
  }
  // resize keeps the slot's capacity: no allocation once the slot has held a frame this large
  const std::size_t before = slot->capacity();
  slot->resize(n);
  retained_ += slot->capacity() - before;
  std::copy(head.begin(), head.end(), slot->begin());
  std::copy(body.begin(), body.end(), slot->begin() + static_cast<std::ptrdiff_t>(head.size()));
  bytes_ += n;
  ++counts_.queued;
}

const std::vector<std::uint8_t>* ClientQueue::front() const {
  if (kept_count_ > 0) return &kept_[kept_head_];
  if (bulk_waiting_ == 0) return nullptr;
  for (std::size_t k = 0; k < bulk_.size(); ++k) {
    const std::size_t i = (bulk_next_ + k) % bulk_.size();
    if (bulk_full_[i]) return &bulk_[i];
  }
  return nullptr;
}

void ClientQueue::pop() {
  if (kept_count_ > 0) {
    bytes_ -= kept_[kept_head_].size();
    emptied(kept_[kept_head_]);
    kept_head_ = (kept_head_ + 1) % kept_.size();
    --kept_count_;
    ++counts_.sent;
    return;
  }
  for (std::size_t k = 0; k < bulk_.size(); ++k) {
    const std::size_t i = (bulk_next_ + k) % bulk_.size();
    if (!bulk_full_[i]) continue;
    bytes_ -= bulk_[i].size();
    bulk_full_[i] = false;
    --bulk_waiting_;
    emptied(bulk_[i]);
    bulk_next_ = (i + 1) % bulk_.size();  // round robin over the bulk channels
    ++counts_.sent;
    return;
  }
}

}  // namespace teleop::bridge
