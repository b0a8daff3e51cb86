#include "server/collision/aabb_tree.hpp"

#include "common/util/prewarm.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace teleop::sim::collision {
namespace {

inline double box_area(const double* lo, const double* hi) {
  const double ex = hi[0] - lo[0];
  const double ey = hi[1] - lo[1];
  const double ez = hi[2] - lo[2];
  return 2.0 * (ex * ey + ey * ez + ez * ex);
}

}  // namespace

void AabbTree::build(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xi& tris) {
  options_.max_leaf_triangles = std::clamp(options_.max_leaf_triangles, 1, 8);
  const auto n = static_cast<std::size_t>(tris.cols());
  tris_ = tris;
  tri_index_.resize(n);
  for (std::size_t i = 0; i < n; ++i) tri_index_[i] = static_cast<std::int32_t>(i);
  tri_verts_.resize(3 * n);
  leaf_verts_.resize(3 * n);
  centroids_.resize(3, static_cast<Eigen::Index>(n));
  nodes_.assign(std::max<std::size_t>(1, 2 * n), Node{});
  build_stack_.assign(2 * kMaxDepth + 8, {0, 0, 0, 0});
  leaves_.reserve(n);
  internal_reverse_.reserve(n);
  rebuild_count_ = 0;
  build_recursive_free(x);
  refit(x);
  built_cost_ = cost_;
}

void AabbTree::rebuild(const Eigen::Matrix3Xd& x) {
  build_recursive_free(x);
  refit(x);
  built_cost_ = cost_;
  ++rebuild_count_;
}

bool AabbTree::rebuild_if_degraded(const Eigen::Matrix3Xd& x) {
  refit(x);
  if (quality_ratio() > options_.rebuild_ratio) {
    rebuild(x);
    return true;
  }
  return false;
}

void AabbTree::build_recursive_free(const Eigen::Matrix3Xd& x) {
  const int n = static_cast<int>(tri_index_.size());
  node_count_ = 0;
  depth_ = 0;
  if (n == 0) return;
  // triangle centroids for the split
  for (int t = 0; t < n; ++t) {
    centroids_.col(t) =
        (x.col(tris_(0, t)) + x.col(tris_(1, t)) + x.col(tris_(2, t))) * (1.0 / 3.0);
  }
  // pre-order construction with an explicit stack of {begin, end, parent-if-right, depth}:
  // the right child of a node is popped only after its whole left subtree is laid out.
  int sp = 0;
  build_stack_[static_cast<std::size_t>(sp++)] = {0, n, -1, 1};
  while (sp > 0) {
    const auto item = build_stack_[static_cast<std::size_t>(--sp)];
    const int b = item[0];
    const int e = item[1];
    const int parent = item[2];
    const int d = item[3];
    const int idx = node_count_++;
    Node& node = nodes_[static_cast<std::size_t>(idx)];
    if (parent >= 0) nodes_[static_cast<std::size_t>(parent)].right = idx;
    depth_ = std::max(depth_, d);
    if (e - b <= options_.max_leaf_triangles) {
      node.first = b;
      node.count = e - b;
      node.right = -1;
      continue;
    }
    if (d >= kMaxDepth || sp + 2 > static_cast<int>(build_stack_.size())) {
      throw std::length_error("AabbTree: depth limit exceeded");
    }
    // split the longest axis of the centroid bounds at the median
    Eigen::Vector3d lo = centroids_.col(tri_index_[static_cast<std::size_t>(b)]);
    Eigen::Vector3d hi = lo;
    for (int i = b + 1; i < e; ++i) {
      const auto c = centroids_.col(tri_index_[static_cast<std::size_t>(i)]);
      lo = lo.cwiseMin(c);
      hi = hi.cwiseMax(c);
    }
    int axis = 0;
    (hi - lo).maxCoeff(&axis);
    const int mid = b + (e - b) / 2;
    std::nth_element(tri_index_.begin() + b, tri_index_.begin() + mid, tri_index_.begin() + e,
                     [this, axis](std::int32_t l, std::int32_t r) {
                       return centroids_(axis, l) < centroids_(axis, r);
                     });
    node.count = 0;
    node.first = 0;
    node.right = -1;
    build_stack_[static_cast<std::size_t>(sp++)] = {mid, e, idx, d + 1};  // right, later
    build_stack_[static_cast<std::size_t>(sp++)] = {b, mid, -1, d + 1};   // left, next
  }
  index_leaves(n);
}

/// After a build of `n` triangles: the leaf and internal node lists for the refit sweeps, the
/// vertex ids in leaf order and each leaf's distinct vertices.
void AabbTree::index_leaves(int n) {
  // leaf and internal node lists for the refit sweeps
  leaves_.clear();
  internal_reverse_.clear();
  for (int i = node_count_ - 1; i >= 0; --i) {
    if (nodes_[static_cast<std::size_t>(i)].count > 0) {
      leaves_.push_back(i);
    } else {
      internal_reverse_.push_back(i);
    }
  }
  // vertex ids in leaf order, for cache-friendly refits and leaf tests
  for (int i = 0; i < n; ++i) {
    const int t = tri_index_[static_cast<std::size_t>(i)];
    for (int k = 0; k < 3; ++k) tri_verts_[static_cast<std::size_t>(3 * i + k)] = tris_(k, t);
  }
  // each leaf's distinct vertices: adjacent triangles share them, so a refit reads fewer
  int vslot = 0;
  for (const std::int32_t li : leaves_) {
    Node& nd = nodes_[static_cast<std::size_t>(li)];
    nd.vfirst = vslot;
    for (int k = 3 * nd.first; k < 3 * (nd.first + nd.count); ++k) {
      const std::int32_t v = tri_verts_[static_cast<std::size_t>(k)];
      bool seen = false;
      for (int j = nd.vfirst; j < vslot; ++j)
        seen = seen || leaf_verts_[static_cast<std::size_t>(j)] == v;
      if (!seen) leaf_verts_[static_cast<std::size_t>(vslot++)] = v;
    }
    nd.vcount = vslot - nd.vfirst;
  }
}

void AabbTree::compute_leaf_box(Node& nd, const Eigen::Matrix3Xd& x) const {
  const double* xs = x.data();
  double lo0 = std::numeric_limits<double>::infinity(), lo1 = lo0, lo2 = lo0;
  double hi0 = -lo0, hi1 = -lo0, hi2 = -lo0;
  const std::int32_t* v = leaf_verts_.data() + nd.vfirst;
  for (int k = 0; k < nd.vcount; ++k) {
    const double* p = xs + 3 * static_cast<std::ptrdiff_t>(v[k]);
    lo0 = std::min(lo0, p[0]);
    hi0 = std::max(hi0, p[0]);
    lo1 = std::min(lo1, p[1]);
    hi1 = std::max(hi1, p[1]);
    lo2 = std::min(lo2, p[2]);
    hi2 = std::max(hi2, p[2]);
  }
  nd.lo[0] = lo0;
  nd.lo[1] = lo1;
  nd.lo[2] = lo2;
  nd.hi[0] = hi0;
  nd.hi[1] = hi1;
  nd.hi[2] = hi2;
}

void AabbTree::refit(const Eigen::Matrix3Xd& x) {
  // leaves first (a tight loop over the leaf list), then the internal nodes in reverse
  // pre-order: children always follow their parent, so that sweep is bottom-up
  for (const std::int32_t li : leaves_) compute_leaf_box(nodes_[static_cast<std::size_t>(li)], x);
  double cost = 0.0;
  for (const std::int32_t i : internal_reverse_) {
    Node& nd = nodes_[static_cast<std::size_t>(i)];
    const Node& l = nodes_[static_cast<std::size_t>(i + 1)];
    const Node& r = nodes_[static_cast<std::size_t>(nd.right)];
    for (int k = 0; k < 3; ++k) {
      nd.lo[k] = l.lo[k] < r.lo[k] ? l.lo[k] : r.lo[k];
      nd.hi[k] = l.hi[k] > r.hi[k] ? l.hi[k] : r.hi[k];
    }
    cost += box_area(nd.lo, nd.hi);
  }
  cost_ = cost;
}

double AabbTree::node_box_distance_sq(const Node& n, const Eigen::Vector3d& p) {
  double s = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double d = std::max(0.0, std::max(n.lo[k] - p[k], p[k] - n.hi[k]));
    s += d * d;
  }
  return s;
}

Aabb AabbTree::root_box() const {
  Aabb b;
  if (node_count_ == 0) return b;
  const Node& r = nodes_[0];
  b.lo = Eigen::Vector3d(r.lo[0], r.lo[1], r.lo[2]);
  b.hi = Eigen::Vector3d(r.hi[0], r.hi[1], r.hi[2]);
  return b;
}

void AabbTree::query_aabb(const Aabb& box, std::vector<int>& hits) const {
  hits.clear();
  if (node_count_ == 0) return;
  std::array<std::int32_t, 2 * kMaxDepth + 8> stack;
  int sp = 0;
  stack[static_cast<std::size_t>(sp++)] = 0;
  while (sp > 0) {
    const Node& nd = nodes_[static_cast<std::size_t>(stack[static_cast<std::size_t>(--sp)])];
    bool overlap = true;
    for (int k = 0; k < 3; ++k) {
      if (nd.lo[k] > box.hi[k] || box.lo[k] > nd.hi[k]) overlap = false;
    }
    if (!overlap) continue;
    if (nd.count > 0) {
      for (int i = nd.first; i < nd.first + nd.count; ++i) {
        hits.push_back(tri_index_[static_cast<std::size_t>(i)]);
      }
      continue;
    }
    const auto self = static_cast<std::int32_t>(&nd - nodes_.data());
    stack[static_cast<std::size_t>(sp++)] = nd.right;
    stack[static_cast<std::size_t>(sp++)] = self + 1;
  }
}

void AabbTree::query_sphere(const Eigen::Vector3d& c, double radius_m, const Eigen::Matrix3Xd& x,
                            std::vector<int>& hits) const {
  hits.clear();
  if (node_count_ == 0 || !(radius_m >= 0.0)) return;
  const double r2 = radius_m * radius_m;
  std::array<std::int32_t, 2 * kMaxDepth + 8> stack;
  int sp = 0;
  stack[static_cast<std::size_t>(sp++)] = 0;
  while (sp > 0) {
    const std::int32_t ni = stack[static_cast<std::size_t>(--sp)];
    const Node& nd = nodes_[static_cast<std::size_t>(ni)];
    if (node_box_distance_sq(nd, c) > r2) continue;
    if (nd.count > 0) {
      for (int i = nd.first; i < nd.first + nd.count; ++i) {
        const std::int32_t* v = tri_verts_.data() + 3 * i;
        const TriClosest tc = closest_point_on_triangle(c, x.col(v[0]), x.col(v[1]), x.col(v[2]));
        if (tc.distance_sq <= r2) hits.push_back(tri_index_[static_cast<std::size_t>(i)]);
      }
      continue;
    }
    stack[static_cast<std::size_t>(sp++)] = nd.right;
    stack[static_cast<std::size_t>(sp++)] = ni + 1;
  }
}

void AabbTree::query_segment(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                             const Eigen::Matrix3Xd& x, std::vector<int>& hits) const {
  hits.clear();
  if (node_count_ == 0) return;
  const double pad = 1e-12 * (1.0 + p.cwiseAbs().maxCoeff() + q.cwiseAbs().maxCoeff());
  std::array<std::int32_t, 2 * kMaxDepth + 8> stack;
  int sp = 0;
  stack[static_cast<std::size_t>(sp++)] = 0;
  while (sp > 0) {
    const std::int32_t ni = stack[static_cast<std::size_t>(--sp)];
    const Node& nd = nodes_[static_cast<std::size_t>(ni)];
    if (!segment_intersects_aabb(p, q, Eigen::Vector3d(nd.lo[0], nd.lo[1], nd.lo[2]),
                                 Eigen::Vector3d(nd.hi[0], nd.hi[1], nd.hi[2]), pad)) {
      continue;
    }
    if (nd.count > 0) {
      for (int i = nd.first; i < nd.first + nd.count; ++i) {
        const std::int32_t* v = tri_verts_.data() + 3 * i;
        if (intersect_segment_triangle(p, q, x.col(v[0]), x.col(v[1]), x.col(v[2])).hit) {
          hits.push_back(tri_index_[static_cast<std::size_t>(i)]);
        }
      }
      continue;
    }
    stack[static_cast<std::size_t>(sp++)] = nd.right;
    stack[static_cast<std::size_t>(sp++)] = ni + 1;
  }
}

bool AabbTree::first_segment_hit(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                                 const Eigen::Matrix3Xd& x, MeshSegmentHit& out) const {
  out = MeshSegmentHit{};
  if (node_count_ == 0) return false;
  const double pad = 1e-12 * (1.0 + p.cwiseAbs().maxCoeff() + q.cwiseAbs().maxCoeff());
  double best_w = std::numeric_limits<double>::infinity();
  std::array<std::int32_t, 2 * kMaxDepth + 8> stack;
  int sp = 0;
  stack[static_cast<std::size_t>(sp++)] = 0;
  while (sp > 0) {
    const std::int32_t ni = stack[static_cast<std::size_t>(--sp)];
    const Node& nd = nodes_[static_cast<std::size_t>(ni)];
    // only the part of the segment before the best hit so far can improve it
    const Eigen::Vector3d qq = std::isfinite(best_w) ? Eigen::Vector3d(p + best_w * (q - p)) : q;
    if (!segment_intersects_aabb(p, qq, Eigen::Vector3d(nd.lo[0], nd.lo[1], nd.lo[2]),
                                 Eigen::Vector3d(nd.hi[0], nd.hi[1], nd.hi[2]), pad)) {
      continue;
    }
    if (nd.count > 0) {
      for (int i = nd.first; i < nd.first + nd.count; ++i) {
        const std::int32_t* v = tri_verts_.data() + 3 * i;
        const SegmentHit h =
            intersect_segment_triangle(p, q, x.col(v[0]), x.col(v[1]), x.col(v[2]));
        if (h.hit && h.w < best_w) {
          best_w = h.w;
          out.triangle = tri_index_[static_cast<std::size_t>(i)];
          out.w = h.w;
          out.u = h.u;
          out.v = h.v;
          out.point = h.point;
        }
      }
      continue;
    }
    stack[static_cast<std::size_t>(sp++)] = nd.right;
    stack[static_cast<std::size_t>(sp++)] = ni + 1;
  }
  return out.triangle >= 0;
}

bool AabbTree::closest_point(const Eigen::Vector3d& p, const Eigen::Matrix3Xd& x,
                             double max_distance_m, MeshClosest& out) const {
  out = MeshClosest{};
  if (node_count_ == 0) return false;
  double best = std::isfinite(max_distance_m) ? max_distance_m * max_distance_m
                                              : std::numeric_limits<double>::infinity();
  // depth-first, nearer child first; entries carry their box distance for pruning on pop
  std::array<std::pair<std::int32_t, double>, 2 * kMaxDepth + 8> stack;
  int sp = 0;
  stack[static_cast<std::size_t>(sp++)] = {0, node_box_distance_sq(nodes_[0], p)};
  bool found = false;
  while (sp > 0) {
    const auto [ni, bd] = stack[static_cast<std::size_t>(--sp)];
    if (bd > best) continue;
    const Node& nd = nodes_[static_cast<std::size_t>(ni)];
    if (nd.count > 0) {
      for (int i = nd.first; i < nd.first + nd.count; ++i) {
        const std::int32_t* v = tri_verts_.data() + 3 * i;
        const TriClosest tc = closest_point_on_triangle(p, x.col(v[0]), x.col(v[1]), x.col(v[2]));
        if (tc.distance_sq <= best) {
          best = tc.distance_sq;
          found = true;
          out.triangle = tri_index_[static_cast<std::size_t>(i)];
          out.point = tc.point;
          out.bary = tc.bary;
          out.feature = tc.feature;
        }
      }
      continue;
    }
    const std::int32_t li = ni + 1;
    const std::int32_t ri = nd.right;
    const double dl = node_box_distance_sq(nodes_[static_cast<std::size_t>(li)], p);
    const double dr = node_box_distance_sq(nodes_[static_cast<std::size_t>(ri)], p);
    if (dl <= dr) {
      if (dr <= best) stack[static_cast<std::size_t>(sp++)] = {ri, dr};
      if (dl <= best) stack[static_cast<std::size_t>(sp++)] = {li, dl};
    } else {
      if (dl <= best) stack[static_cast<std::size_t>(sp++)] = {li, dl};
      if (dr <= best) stack[static_cast<std::size_t>(sp++)] = {ri, dr};
    }
  }
  if (found) out.distance_m = std::sqrt(best);
  return found;
}

std::uint64_t AabbTree::touch() const {
  return teleop::touch_lines(nodes_.data(), static_cast<std::size_t>(node_count_) * sizeof(Node)) +
         teleop::touch(leaves_) + teleop::touch(internal_reverse_) + teleop::touch(tri_index_) +
         teleop::touch(tri_verts_) + teleop::touch(leaf_verts_) + teleop::touch(tris_);
}

}  // namespace teleop::sim::collision
