#pragma once
// Broad phase over the scene's objects: each object is an AABB (refreshed by the caller every
// step, e.g. from AabbTree::root_box() or a link's box); overlapping pairs are found by sort
// and sweep along x. Memory is sized by reserve(); update() and pairs() allocate nothing
// while the object count stays within it.
#include <utility>
#include <vector>

#include "server/collision/geometry.hpp"

namespace teleop::sim::collision {

/// Sort-and-sweep broad phase over object boxes.
class BroadPhase {
 public:
  /// Sizes the tables for up to `max_objects` objects. Allocates.
  void reserve(int max_objects);
  /// Adds an object with scene id `id`; @return its slot.
  int add(int id, const Aabb& box);
  /// Replaces the box of slot `slot`.
  void update(int slot, const Aabb& box) { boxes_[static_cast<std::size_t>(slot)] = box; }
  /// Grows every box by margin_m on each side before testing (swept or tolerance).
  void set_margin(double margin_m) { margin_m_ = margin_m; }
  int size() const { return static_cast<int>(ids_.size()); }

  /// Overlapping pairs as (id, id) with the smaller slot first; clears `out`.
  void pairs(std::vector<std::pair<int, int>>& out);

 private:
  std::vector<int> ids_;
  std::vector<Aabb> boxes_;
  std::vector<int> order_;
  double margin_m_ = 0.0;
};

}  // namespace teleop::sim::collision
