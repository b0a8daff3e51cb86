#include "server/collision/surface_topology.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>

namespace teleop::sim::collision {

void SurfaceTopology::build(const Eigen::Matrix3Xi& tris, int vertex_count) {
  tris_ = tris;
  vertex_count_ = vertex_count;
  const auto nt = static_cast<int>(tris.cols());
  if (nt > 0 && (tris.minCoeff() < 0 || tris.maxCoeff() >= vertex_count)) {
    throw std::invalid_argument("SurfaceTopology: triangle index out of range");
  }
  // vertex -> triangles (CSR)
  vt_offset_.assign(static_cast<std::size_t>(vertex_count) + 1, 0);
  for (int t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) ++vt_offset_[static_cast<std::size_t>(tris(k, t)) + 1];
  }
  for (int v = 0; v < vertex_count; ++v) {
    vt_offset_[static_cast<std::size_t>(v) + 1] += vt_offset_[static_cast<std::size_t>(v)];
  }
  vt_tris_.assign(static_cast<std::size_t>(3 * nt), -1);
  std::vector<std::int32_t> fill(vt_offset_.begin(), vt_offset_.end() - 1);
  for (int t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      vt_tris_[static_cast<std::size_t>(fill[static_cast<std::size_t>(tris(k, t))]++)] = t;
    }
  }
  // triangle neighbours across each directed edge: the twin of (a->b) is (b->a)
  nbr_.setConstant(3, nt, -1);
  std::unordered_map<std::uint64_t, std::int32_t> directed;
  directed.reserve(static_cast<std::size_t>(3 * nt));
  auto key = [](std::uint64_t a, std::uint64_t b) { return (a << 32) | b; };
  closed_ = nt > 0;
  for (int t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      const auto a = static_cast<std::uint64_t>(tris(k, t));
      const auto b = static_cast<std::uint64_t>(tris((k + 1) % 3, t));
      if (!directed.emplace(key(a, b), 3 * t + k).second) closed_ = false;  // non-manifold
    }
  }
  for (int t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      const auto a = static_cast<std::uint64_t>(tris(k, t));
      const auto b = static_cast<std::uint64_t>(tris((k + 1) % 3, t));
      const auto it = directed.find(key(b, a));
      if (it == directed.end()) {
        closed_ = false;
      } else {
        nbr_(k, t) = it->second / 3;
      }
    }
  }
}

Eigen::Vector3d SurfaceTopology::face_normal(const Eigen::Matrix3Xd& x, int t) const {
  const Eigen::Vector3d n =
      triangle_normal_raw(x.col(tris_(0, t)), x.col(tris_(1, t)), x.col(tris_(2, t)));
  const double l = n.norm();
  return l > 0.0 ? Eigen::Vector3d(n / l) : Eigen::Vector3d::Zero();
}

Eigen::Vector3d SurfaceTopology::vertex_normal(const Eigen::Matrix3Xd& x, int v) const {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (int i = vt_offset_[static_cast<std::size_t>(v)];
       i < vt_offset_[static_cast<std::size_t>(v) + 1]; ++i) {
    const int t = vt_tris_[static_cast<std::size_t>(i)];
    n += triangle_normal_raw(x.col(tris_(0, t)), x.col(tris_(1, t)), x.col(tris_(2, t)));
  }
  const double l = n.norm();
  return l > 0.0 ? Eigen::Vector3d(n / l) : Eigen::Vector3d::Zero();
}

Eigen::Vector3d SurfaceTopology::pseudo_normal(const Eigen::Matrix3Xd& x, int t,
                                               TriFeature feature) const {
  switch (feature) {
    case TriFeature::kFace:
      return face_normal(x, t);
    case TriFeature::kEdge01:
    case TriFeature::kEdge12:
    case TriFeature::kEdge20: {
      const int k = feature == TriFeature::kEdge01 ? 0 : (feature == TriFeature::kEdge12 ? 1 : 2);
      const int o = nbr_(k, t);
      Eigen::Vector3d n = face_normal(x, t);
      if (o >= 0) n += face_normal(x, o);
      return n;
    }
    default: {
      const int k = static_cast<int>(feature) - static_cast<int>(TriFeature::kVertex0);
      const int v = tris_(k, t);
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      for (int i = vt_offset_[static_cast<std::size_t>(v)];
           i < vt_offset_[static_cast<std::size_t>(v) + 1]; ++i) {
        const int s = vt_tris_[static_cast<std::size_t>(i)];
        int c = 0;
        while (c < 3 && tris_(c, s) != v) ++c;
        const Eigen::Vector3d p = x.col(v);
        const Eigen::Vector3d e1 = x.col(tris_((c + 1) % 3, s)) - p;
        const Eigen::Vector3d e2 = x.col(tris_((c + 2) % 3, s)) - p;
        const double l1 = e1.norm();
        const double l2 = e2.norm();
        if (l1 <= 0.0 || l2 <= 0.0) continue;
        const double angle = std::acos(std::clamp(e1.dot(e2) / (l1 * l2), -1.0, 1.0));
        n += angle * face_normal(x, s);
      }
      return n;
    }
  }
}

Eigen::Vector3d SurfaceTopology::smooth_normal(const Eigen::Matrix3Xd& x, int t,
                                               const Eigen::Vector3d& bary,
                                               double crease_cos) const {
  const Eigen::Vector3d nt = face_normal(x, t);
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (int k = 0; k < 3; ++k) {
    const int v = tris_(k, t);
    Eigen::Vector3d vn = Eigen::Vector3d::Zero();
    for (int i = vt_offset_[static_cast<std::size_t>(v)];
         i < vt_offset_[static_cast<std::size_t>(v) + 1]; ++i) {
      const int s = vt_tris_[static_cast<std::size_t>(i)];
      const Eigen::Vector3d ns =
          triangle_normal_raw(x.col(tris_(0, s)), x.col(tris_(1, s)), x.col(tris_(2, s)));
      const double l = ns.norm();
      if (l > 0.0 && ns.dot(nt) >= crease_cos * l) vn += ns;
    }
    const double l = vn.norm();
    n += bary[k] * (l > 0.0 ? Eigen::Vector3d(vn / l) : nt);
  }
  const double l = n.norm();
  if (l > 1e-12) return n / l;
  return nt;
}

}  // namespace teleop::sim::collision
