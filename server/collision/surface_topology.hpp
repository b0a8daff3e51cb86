#pragma once
// Adjacency of a triangle mesh needed for robust inside/outside tests: the triangles around
// each vertex (CSR) and the neighbour across each triangle edge. With it the angle-weighted
// pseudo-normal (Baerentzen & Aanaes 2005) of the closest feature decides the side of a point
// exactly for a closed, consistently oriented (CCW from outside) mesh.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "server/collision/geometry.hpp"

namespace teleop::sim::collision {

/// Vertex-triangle and triangle-triangle adjacency of a fixed topology.
class SurfaceTopology {
 public:
  /// Builds the tables for `tris` over `vertex_count` vertices. Allocates.
  void build(const Eigen::Matrix3Xi& tris, int vertex_count);

  /// True when every edge is shared by exactly two triangles with opposite directions (a
  /// closed, consistently oriented 2-manifold): then "inside" is well defined.
  bool closed() const { return closed_; }
  int vertex_count() const { return vertex_count_; }
  int triangle_count() const { return static_cast<int>(tris_.cols()); }
  const Eigen::Matrix3Xi& triangles() const { return tris_; }

  /// Triangle across edge k of triangle t (edge k joins corner k and corner (k+1)%3), or -1.
  int neighbour(int t, int k) const { return nbr_(k, t); }

  /// Number of triangles around vertex v.
  int vertex_triangle_count(int v) const {
    return vt_offset_[static_cast<std::size_t>(v) + 1] - vt_offset_[static_cast<std::size_t>(v)];
  }
  /// The i-th triangle around vertex v (0 <= i < vertex_triangle_count(v)).
  int vertex_triangle(int v, int i) const {
    return vt_tris_[static_cast<std::size_t>(vt_offset_[static_cast<std::size_t>(v)] + i)];
  }

  /// Unit outward normal of triangle t at positions x (zero for a degenerate triangle).
  Eigen::Vector3d face_normal(const Eigen::Matrix3Xd& x, int t) const;

  /// Area-weighted unit normal at vertex v (for smooth interpolated contact normals).
  Eigen::Vector3d vertex_normal(const Eigen::Matrix3Xd& x, int v) const;

  /// Angle-weighted pseudo-normal (not normalised) of `feature` of triangle t.
  Eigen::Vector3d pseudo_normal(const Eigen::Matrix3Xd& x, int t, TriFeature feature) const;

  /// Normal interpolated from the three vertex normals of triangle t with barycentric
  /// weights `bary`, normalised (Phong normal: continuous across smooth edges). Each vertex
  /// normal only averages the incident triangles whose normal lies within the crease angle of
  /// t's own (cos >= crease_cos), so sharp edges (a box) keep their flat faces.
  Eigen::Vector3d smooth_normal(const Eigen::Matrix3Xd& x, int t, const Eigen::Vector3d& bary,
                                double crease_cos = 0.866) const;

 private:
  Eigen::Matrix3Xi tris_;
  Eigen::Matrix3Xi nbr_;
  std::vector<std::int32_t> vt_offset_;  ///< CSR offsets, size vertex_count + 1
  std::vector<std::int32_t> vt_tris_;    ///< triangles around each vertex
  int vertex_count_ = 0;
  bool closed_ = false;
};

}  // namespace teleop::sim::collision
