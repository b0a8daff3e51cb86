#include "server/collision/broad_phase.hpp"

#include <algorithm>

namespace teleop::sim::collision {

void BroadPhase::reserve(int max_objects) {
  const auto n = static_cast<std::size_t>(std::max(0, max_objects));
  ids_.reserve(n);
  boxes_.reserve(n);
  order_.reserve(n);
}

int BroadPhase::add(int id, const Aabb& box) {
  ids_.push_back(id);
  boxes_.push_back(box);
  order_.push_back(static_cast<int>(order_.size()));
  return static_cast<int>(ids_.size()) - 1;
}

void BroadPhase::pairs(std::vector<std::pair<int, int>>& out) {
  out.clear();
  const double m = margin_m_;
  // insertion sort on lo.x: the order barely changes between steps (coherence), O(n) then
  for (std::size_t i = 1; i < order_.size(); ++i) {
    const int v = order_[i];
    std::size_t j = i;
    while (j > 0 && boxes_[static_cast<std::size_t>(order_[j - 1])].lo.x() >
                        boxes_[static_cast<std::size_t>(v)].lo.x()) {
      order_[j] = order_[j - 1];
      --j;
    }
    order_[j] = v;
  }
  for (std::size_t a = 0; a < order_.size(); ++a) {
    const Aabb& ba = boxes_[static_cast<std::size_t>(order_[a])];
    if (ba.is_empty()) continue;
    for (std::size_t b = a + 1; b < order_.size(); ++b) {
      const Aabb& bb = boxes_[static_cast<std::size_t>(order_[b])];
      if (bb.lo.x() - m > ba.hi.x() + m) break;  // sorted: nothing further can overlap in x
      if (bb.is_empty()) continue;
      bool overlap = true;
      for (int k = 0; k < 3; ++k) {
        if (ba.lo[k] - m > bb.hi[k] + m || bb.lo[k] - m > ba.hi[k] + m) overlap = false;
      }
      if (!overlap) continue;
      int s0 = order_[a];
      int s1 = order_[b];
      if (s0 > s1) std::swap(s0, s1);
      out.emplace_back(ids_[static_cast<std::size_t>(s0)], ids_[static_cast<std::size_t>(s1)]);
    }
  }
}

}  // namespace teleop::sim::collision
