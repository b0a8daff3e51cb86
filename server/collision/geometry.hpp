#pragma once
// Exact primitive tests used by the collision module: point-triangle closest point, segment-
// triangle intersection (the paper's eq. (8)), AABB helpers, and the generalised winding number
// of a closed triangle mesh (the brute-force inside/outside reference).
//
// All functions are pure, allocate nothing and work in metres.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

namespace teleop::sim::collision {

/// Which feature of a triangle a closest point lies on.
enum class TriFeature : std::uint8_t {
  kFace = 0,     ///< interior of the face
  kVertex0 = 1,  ///< vertex a
  kVertex1 = 2,  ///< vertex b
  kVertex2 = 3,  ///< vertex c
  kEdge01 = 4,   ///< edge a-b (open)
  kEdge12 = 5,   ///< edge b-c (open)
  kEdge20 = 6,   ///< edge c-a (open)
};

/// Closest point of a triangle to a query point.
struct TriClosest {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< closest point on the triangle [m]
  Eigen::Vector3d bary = Eigen::Vector3d::Zero();   ///< barycentric weights of `point` (sum 1)
  double distance_sq = 0.0;                         ///< squared distance to the query [m^2]
  TriFeature feature = TriFeature::kFace;           ///< the feature `point` lies on
};

/// Exact closest point on triangle (a, b, c) to p (Voronoi-region walk, after Ericson,
/// Real-Time Collision Detection, 5.1.5). Degenerate triangles are handled (the result is
/// still a point of the triangle's convex hull).
TriClosest closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                     const Eigen::Vector3d& b, const Eigen::Vector3d& c);

/// Result of a segment-triangle intersection, the paper's eq. (8):
///   P + w (P0 - P) = A + (B - A) u + (C - A) v,
/// solved for (u, v, w) by Cramer's rule. The hit point is P(w).
struct SegmentHit {
  bool hit = false;
  double w = 0.0;  ///< segment parameter in [0, 1] (0 at the start point)
  double u = 0.0;  ///< barycentric weight of B
  double v = 0.0;  ///< barycentric weight of C
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  ///< P(w) [m]
};

/// Intersects segment p -> q with triangle (a, b, c), both sides, closed triangle (u, v >= 0,
/// u + v <= 1, with a relative tolerance `eps` that widens the triangle slightly so that a
/// segment through a shared edge or vertex hits at least one of the triangles). Segments
/// parallel to the plane (|det| tiny) never hit.
SegmentHit intersect_segment_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                                      const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                      const Eigen::Vector3d& c, double eps = 1e-12);

/// Unnormalised normal (b - a) x (c - a) of a triangle; length = 2 x area [m^2].
inline Eigen::Vector3d triangle_normal_raw(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                           const Eigen::Vector3d& c) {
  return (b - a).cross(c - a);
}

/// Signed solid angle [sr] subtended at p by triangle (a, b, c) (Van Oosterom & Strackee 1983);
/// positive when p lies on the side opposite to the normal (b - a) x (c - a), i.e. on the
/// inner side of a triangle wound counter-clockwise seen from outside.
double triangle_solid_angle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                            const Eigen::Vector3d& b, const Eigen::Vector3d& c);

/// Generalised winding number of point p with respect to the closed mesh (x, tris): about 1
/// inside, about 0 outside (Jacobson et al. 2013). O(triangles): a reference, not a hot path.
double winding_number(const Eigen::Vector3d& p, const Eigen::Matrix3Xd& x,
                      const Eigen::Matrix3Xi& tris);

/// Axis-aligned box [lo, hi] in metres.
struct Aabb {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1.0);
  Eigen::Vector3d hi = Eigen::Vector3d::Constant(-1.0);

  /// An empty box (lo > hi) that grows with extend().
  static Aabb empty() { return Aabb{}; }
  bool is_empty() const { return (lo.array() > hi.array()).any(); }
  void extend(const Eigen::Vector3d& p) {
    if (is_empty()) {
      lo = hi = p;
    } else {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  void extend(const Aabb& o) {
    if (o.is_empty()) return;
    if (is_empty()) {
      *this = o;
    } else {
      lo = lo.cwiseMin(o.lo);
      hi = hi.cwiseMax(o.hi);
    }
  }
  /// True when the two closed boxes share a point.
  bool overlaps(const Aabb& o) const {
    return (lo.array() <= o.hi.array()).all() && (o.lo.array() <= hi.array()).all();
  }
  /// Squared distance from p to the box (0 inside) [m^2].
  double distance_sq(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d d =
        (lo - p).cwiseMax(Eigen::Vector3d::Zero()) + (p - hi).cwiseMax(Eigen::Vector3d::Zero());
    return d.squaredNorm();
  }
  /// Surface area [m^2] (0 for an empty box).
  double surface_area() const {
    if (is_empty()) return 0.0;
    const Eigen::Vector3d e = hi - lo;
    return 2.0 * (e.x() * e.y() + e.y() * e.z() + e.z() * e.x());
  }
};

/// Slab test: does segment p -> q pass through box `b` grown by `inflate` on every side?
bool segment_intersects_aabb(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                             const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double inflate);

}  // namespace teleop::sim::collision
