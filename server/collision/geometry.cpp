#include "server/collision/geometry.hpp"

#include <algorithm>
#include <cmath>

namespace teleop::sim::collision {

TriClosest closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                     const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  TriClosest r;
  const Eigen::Vector3d ab = b - a;
  const Eigen::Vector3d ac = c - a;
  const Eigen::Vector3d ap = p - a;
  auto finish = [&](const Eigen::Vector3d& q, double wa, double wb, double wc, TriFeature f) {
    r.point = q;
    r.bary = Eigen::Vector3d(wa, wb, wc);
    r.distance_sq = (p - q).squaredNorm();
    r.feature = f;
    return r;
  };
  // vertex region a
  const double d1 = ab.dot(ap);
  const double d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return finish(a, 1, 0, 0, TriFeature::kVertex0);
  // vertex region b
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp);
  const double d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return finish(b, 0, 1, 0, TriFeature::kVertex1);
  // edge region ab
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double den = d1 - d3;
    const double v = den > 0.0 ? d1 / den : 0.0;
    return finish(a + v * ab, 1.0 - v, v, 0.0, TriFeature::kEdge01);
  }
  // vertex region c
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp);
  const double d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return finish(c, 0, 0, 1, TriFeature::kVertex2);
  // edge region ac
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double den = d2 - d6;
    const double w = den > 0.0 ? d2 / den : 0.0;
    return finish(a + w * ac, 1.0 - w, 0.0, w, TriFeature::kEdge20);
  }
  // edge region bc
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double den = (d4 - d3) + (d5 - d6);
    const double w = den > 0.0 ? (d4 - d3) / den : 0.0;
    return finish(b + w * (c - b), 0.0, 1.0 - w, w, TriFeature::kEdge12);
  }
  // face region
  const double sum = va + vb + vc;
  if (!(sum > 0.0)) {
    // degenerate (zero-area) triangle: fall back to the closest of its three edges
    TriClosest best = finish(a, 1, 0, 0, TriFeature::kVertex0);
    auto edge = [&](const Eigen::Vector3d& e0, const Eigen::Vector3d& e1, int i0, int i1,
                    TriFeature f) {
      const Eigen::Vector3d e = e1 - e0;
      const double len2 = e.squaredNorm();
      const double t = len2 > 0.0 ? std::clamp((p - e0).dot(e) / len2, 0.0, 1.0) : 0.0;
      const Eigen::Vector3d q = e0 + t * e;
      const double d2q = (p - q).squaredNorm();
      if (d2q < best.distance_sq) {
        best.point = q;
        best.bary.setZero();
        best.bary[i0] = 1.0 - t;
        best.bary[i1] = t;
        best.distance_sq = d2q;
        best.feature = f;
      }
    };
    edge(a, b, 0, 1, TriFeature::kEdge01);
    edge(b, c, 1, 2, TriFeature::kEdge12);
    edge(c, a, 2, 0, TriFeature::kEdge20);
    return best;
  }
  const double denom = 1.0 / sum;
  const double v = vb * denom;
  const double w = vc * denom;
  return finish(a + ab * v + ac * w, 1.0 - v - w, v, w, TriFeature::kFace);
}

SegmentHit intersect_segment_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                                      const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                      const Eigen::Vector3d& c, double eps) {
  // eq. (8): p + w (q - p) = a + u (b - a) + v (c - a)
  //  <=>  [-(q - p), b - a, c - a] [w u v]^T = p - a, solved by Cramer's rule.
  SegmentHit h;
  const Eigen::Vector3d d = q - p;
  const Eigen::Vector3d e1 = b - a;
  const Eigen::Vector3d e2 = c - a;
  const Eigen::Vector3d s = p - a;
  const Eigen::Vector3d n = e1.cross(e2);
  const double det = -d.dot(n);  // det[-d, e1, e2]
  const double scale = d.norm() * n.norm();
  if (!(std::abs(det) > 1e-14 * scale) || scale == 0.0) return h;
  const double inv = 1.0 / det;
  const double w = s.dot(n) * inv;             // det[s, e1, e2] / det
  const double u = -d.dot(s.cross(e2)) * inv;  // det[-d, s, e2] / det
  const double v = -d.dot(e1.cross(s)) * inv;  // det[-d, e1, s] / det
  if (w < 0.0 || w > 1.0) return h;
  if (u < -eps || v < -eps || u + v > 1.0 + eps) return h;
  h.hit = true;
  h.w = w;
  h.u = u;
  h.v = v;
  h.point = p + w * d;
  return h;
}

double triangle_solid_angle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                            const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ra = a - p;
  const Eigen::Vector3d rb = b - p;
  const Eigen::Vector3d rc = c - p;
  const double la = ra.norm();
  const double lb = rb.norm();
  const double lc = rc.norm();
  const double num = ra.dot(rb.cross(rc));
  const double den = la * lb * lc + ra.dot(rb) * lc + rb.dot(rc) * la + rc.dot(ra) * lb;
  return 2.0 * std::atan2(num, den);
}

double winding_number(const Eigen::Vector3d& p, const Eigen::Matrix3Xd& x,
                      const Eigen::Matrix3Xi& tris) {
  double sum = 0.0;
  for (Eigen::Index t = 0; t < tris.cols(); ++t) {
    sum += triangle_solid_angle(p, x.col(tris(0, t)), x.col(tris(1, t)), x.col(tris(2, t)));
  }
  return sum / (4.0 * M_PI);
}

bool segment_intersects_aabb(const Eigen::Vector3d& p, const Eigen::Vector3d& q,
                             const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, double inflate) {
  double t0 = 0.0;
  double t1 = 1.0;
  for (int i = 0; i < 3; ++i) {
    const double l = lo[i] - inflate;
    const double h = hi[i] + inflate;
    const double d = q[i] - p[i];
    if (std::abs(d) < 1e-300) {
      if (p[i] < l || p[i] > h) return false;
      continue;
    }
    const double inv = 1.0 / d;
    double ta = (l - p[i]) * inv;
    double tb = (h - p[i]) * inv;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  return true;
}

}  // namespace teleop::sim::collision
