#pragma once
// AABB binary tree over the triangles of a deforming mesh (van den Bergen 1997): built once
// top-down (median split on the longest axis of the centroid bounds), refitted bottom-up in
// O(n) every step, and rebuilt when its quality (summed surface area of the internal boxes)
// has grown past a threshold relative to the last build.
//
// Memory is sized by build(); refit(), rebuild(), rebuild_if_degraded() and every query
// allocate nothing (query results go into caller vectors whose capacity was reserved: pass
// a vector with capacity >= triangle_count() to be allocation-free).
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "server/collision/geometry.hpp"

namespace teleop::sim::collision {

/// Closest point of a mesh to a query point.
struct MeshClosest {
  int triangle = -1;                                ///< triangle index, -1 when none found
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< closest point on the mesh [m]
  Eigen::Vector3d bary = Eigen::Vector3d::Zero();   ///< barycentric weights on `triangle`
  double distance_m = 0.0;                          ///< unsigned distance to the query [m]
  TriFeature feature = TriFeature::kFace;           ///< feature of `triangle` it lies on
};

/// First intersection of a segment with the mesh (eq. (8)).
struct MeshSegmentHit {
  int triangle = -1;  ///< triangle hit first, -1 when the segment misses
  double w = 0.0;     ///< segment parameter of the hit in [0, 1]
  double u = 0.0;     ///< barycentric weight of the triangle's second vertex
  double v = 0.0;     ///< barycentric weight of the triangle's third vertex
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< P(w) [m]
};

/// Bounding-volume hierarchy of axis-aligned boxes over a triangle mesh.
class AabbTree {
 public:
  /// Build options.
  struct Options {
    int max_leaf_triangles = 8;  ///< triangles per leaf (1..8)
    double rebuild_ratio = 1.5;  ///< rebuild when quality_ratio() exceeds this [-]
  };

  AabbTree() = default;
  explicit AabbTree(Options options) : options_(options) {}

  /// Sizes all memory and builds the tree over `tris` (3 x T vertex indices into `x`, 3 x N
  /// positions [m]). Allocates. The topology is copied; later calls use only positions.
  void build(const Eigen::Matrix3Xd& x, const Eigen::Matrix3Xi& tris);

  /// Recomputes every box bottom-up for new positions `x` (same topology). O(n), no
  /// allocation. Also updates quality_ratio().
  void refit(const Eigen::Matrix3Xd& x);

  /// Rebuilds the hierarchy in place for positions `x` (same topology). O(n log n), no
  /// allocation.
  void rebuild(const Eigen::Matrix3Xd& x);

  /// refit(x), then rebuild(x) when quality_ratio() > options.rebuild_ratio.
  /// @return true when it rebuilt.
  bool rebuild_if_degraded(const Eigen::Matrix3Xd& x);

  /// Sum of internal box surface areas now, divided by the same sum right after the last
  /// build or rebuild (1 after a build; grows as the mesh deforms) [-].
  double quality_ratio() const { return built_cost_ > 0.0 ? cost_ / built_cost_ : 1.0; }

  /// Triangles whose exact distance to the point c is <= radius_m (positions `x` must be the
  /// ones last refitted). Appends to `hits` after clearing it; order unspecified.
  void query_sphere(const Eigen::Vector3d& c, double radius_m, const Eigen::Matrix3Xd& x,
                    std::vector<int>& hits) const;

  /// Triangles whose box overlaps `box` (candidates only, no exact test). Clears `hits`.
  void query_aabb(const Aabb& box, std::vector<int>& hits) const;

  /// Triangles that segment p -> q intersects (eq. (8), exact). Clears `hits`.
  void query_segment(const Eigen::Vector3d& p, const Eigen::Vector3d& q, const Eigen::Matrix3Xd& x,
                     std::vector<int>& hits) const;

  /// First triangle along segment p -> q (smallest w). @return false when it misses.
  bool first_segment_hit(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                         const Eigen::Matrix3Xd& x, MeshSegmentHit& out) const;

  /// Closest point of the mesh to p, searched within max_distance_m (use infinity for no
  /// bound). @return false when no triangle lies within the bound.
  bool closest_point(const Eigen::Vector3d& p, const Eigen::Matrix3Xd& x, double max_distance_m,
                     MeshClosest& out) const;

  /// Box around the whole mesh as of the last refit.
  Aabb root_box() const;

  int triangle_count() const { return static_cast<int>(tri_index_.size()); }
  int node_count() const { return node_count_; }
  /// Depth of the deepest leaf (root = 1).
  int depth() const { return depth_; }
  /// Number of rebuilds since build().
  std::uint64_t rebuild_count() const { return rebuild_count_; }
  /// Reads the arrays a query and a refit use into the caches (common/util/prewarm.hpp);
  /// changes nothing. Returns the sum of the bytes read.
  std::uint64_t touch() const;
  const Options& options() const { return options_; }

  /// Maximum supported depth: build() throws std::length_error past it (never for meshes
  /// below 2^60 triangles with a median split).
  static constexpr int kMaxDepth = 120;

 private:
  struct Node {
    double lo[3];
    double hi[3];
    std::int32_t right = -1;  ///< internal: index of the right child (left is this + 1)
    std::int32_t first = 0;   ///< leaf: first slot in tri_index_
    std::int32_t count = 0;   ///< leaf: triangle count (0 for internal nodes)
    std::int32_t vfirst = 0;  ///< leaf: first slot in leaf_verts_ (its distinct vertices)
    std::int32_t vcount = 0;  ///< leaf: number of distinct vertices
  };

  void build_recursive_free(const Eigen::Matrix3Xd& x);
  void index_leaves(int n);
  void compute_leaf_box(Node& n, const Eigen::Matrix3Xd& x) const;
  static double node_box_distance_sq(const Node& n, const Eigen::Vector3d& p);

  Options options_{};
  std::vector<Node> nodes_;
  int node_count_ = 0;
  int depth_ = 0;
  std::vector<std::int32_t> leaves_;            ///< leaf node ids
  std::vector<std::int32_t> internal_reverse_;  ///< internal node ids, children first
  std::vector<std::int32_t> tri_index_;         ///< triangle ids in leaf order
  std::vector<std::int32_t> tri_verts_;         ///< 3 vertex ids per slot, in leaf order
  std::vector<std::int32_t> leaf_verts_;        ///< distinct vertex ids of each leaf (for refits)
  Eigen::Matrix3Xi tris_;                       ///< copy of the topology (original order)
  Eigen::Matrix3Xd centroids_;                  ///< scratch for (re)builds
  std::vector<std::array<std::int32_t, 4>> build_stack_;  ///< scratch for (re)builds
  double cost_ = 0.0;
  double built_cost_ = 0.0;
  std::uint64_t rebuild_count_ = 0;
};

}  // namespace teleop::sim::collision
