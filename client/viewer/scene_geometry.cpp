#include "client/viewer/scene_geometry.hpp"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

namespace teleop::viewer {
namespace {

constexpr float kPi = 3.14159265358979f;

/// Two unit vectors spanning the plane with normal n, chosen along world axes when possible so
/// grids line up with the scene: u x v = n.
void plane_basis(const Eigen::Vector3f& n, Eigen::Vector3f& u, Eigen::Vector3f& v) {
  const Eigen::Vector3f helper =
      std::abs(n.z()) > 0.9f ? Eigen::Vector3f::UnitX() : Eigen::Vector3f::UnitZ();
  v = (helper - helper.dot(n) * n).normalized();
  u = v.cross(n).normalized();
}

/// Keeps the part of a convex polygon on the free side of `plane` (Sutherland-Hodgman).
std::vector<Eigen::Vector3f> clip_polygon(const std::vector<Eigen::Vector3f>& poly,
                                          const Plane& plane) {
  std::vector<Eigen::Vector3f> out;
  const std::size_t n = poly.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f& a = poly[i];
    const Eigen::Vector3f& b = poly[(i + 1) % n];
    const float da = plane.normal.dot(a) - plane.offset_m;
    const float db = plane.normal.dot(b) - plane.offset_m;
    if (da >= 0.0f) out.push_back(a);
    if ((da >= 0.0f) != (db >= 0.0f)) out.push_back(a + (b - a) * (da / (da - db)));
  }
  return out;
}

/// Clips segment [a, b] to the free side of `plane`; false if nothing is left.
bool clip_segment(Eigen::Vector3f& a, Eigen::Vector3f& b, const Plane& plane) {
  const float da = plane.normal.dot(a) - plane.offset_m;
  const float db = plane.normal.dot(b) - plane.offset_m;
  if (da < 0.0f && db < 0.0f) return false;
  if (da < 0.0f) a = a + (b - a) * (da / (da - db));
  if (db < 0.0f) b = b + (a - b) * (db / (db - da));
  return true;
}

void add_triangle(PrimitiveMesh& m, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
  m.indices.push_back(a);
  m.indices.push_back(b);
  m.indices.push_back(c);
}

std::uint32_t add_vertex(PrimitiveMesh& m, const Eigen::Vector3f& p, const Eigen::Vector3f& n) {
  m.positions.push_back(p);
  m.normals.push_back(n);
  return static_cast<std::uint32_t>(m.positions.size() - 1);
}

/// A disc cap at height z facing `up` (true: +z).
void add_cap(PrimitiveMesh& m, int segments, float z, bool up) {
  const Eigen::Vector3f n(0.0f, 0.0f, up ? 1.0f : -1.0f);
  const std::uint32_t centre = add_vertex(m, Eigen::Vector3f(0.0f, 0.0f, z), n);
  const std::uint32_t first = static_cast<std::uint32_t>(m.positions.size());
  for (int i = 0; i < segments; ++i) {
    const float a = 2.0f * kPi * static_cast<float>(i) / static_cast<float>(segments);
    add_vertex(m, Eigen::Vector3f(std::cos(a), std::sin(a), z), n);
  }
  for (int i = 0; i < segments; ++i) {
    const auto s = static_cast<std::uint32_t>(segments);
    const std::uint32_t a = first + static_cast<std::uint32_t>(i);
    const std::uint32_t b = first + (static_cast<std::uint32_t>(i) + 1) % s;
    if (up) {
      add_triangle(m, centre, a, b);
    } else {
      add_triangle(m, centre, b, a);
    }
  }
}

}  // namespace

PrimitiveMesh make_sphere(int subdivisions) {
  PrimitiveMesh m;
  const float t = (1.0f + std::sqrt(5.0f)) / 2.0f;
  const std::array<Eigen::Vector3f, 12> ico = {
      Eigen::Vector3f(-1, t, 0),  Eigen::Vector3f(1, t, 0),   Eigen::Vector3f(-1, -t, 0),
      Eigen::Vector3f(1, -t, 0),  Eigen::Vector3f(0, -1, t),  Eigen::Vector3f(0, 1, t),
      Eigen::Vector3f(0, -1, -t), Eigen::Vector3f(0, 1, -t),  Eigen::Vector3f(t, 0, -1),
      Eigen::Vector3f(t, 0, 1),   Eigen::Vector3f(-t, 0, -1), Eigen::Vector3f(-t, 0, 1)};
  for (const auto& p : ico) add_vertex(m, p.normalized(), p.normalized());
  m.indices = {0, 11, 5,  0, 5,  1, 0, 1, 7, 0, 7,  10, 0, 10, 11, 1, 5, 9, 5, 11,
               4, 11, 10, 2, 10, 7, 6, 7, 1, 8, 3,  9,  4, 3,  4,  2, 3, 2, 6, 3,
               6, 8,  3,  8, 9,  4, 9, 5, 2, 4, 11, 6,  2, 10, 8,  6, 7, 9, 8, 1};
  for (int level = 0; level < subdivisions; ++level) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> midpoint;
    auto mid = [&](std::uint32_t a, std::uint32_t b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      const auto it = midpoint.find(key);
      if (it != midpoint.end()) return it->second;
      const Eigen::Vector3f p = (m.positions[a] + m.positions[b]).normalized();
      const std::uint32_t i = add_vertex(m, p, p);
      midpoint.emplace(key, i);
      return i;
    };
    std::vector<std::uint32_t> next;
    next.reserve(m.indices.size() * 4);
    for (std::size_t k = 0; k < m.indices.size(); k += 3) {
      const std::uint32_t a = m.indices[k], b = m.indices[k + 1], c = m.indices[k + 2];
      const std::uint32_t ab = mid(a, b), bc = mid(b, c), ca = mid(c, a);
      next.insert(next.end(), {a, ab, ca, b, bc, ab, c, ca, bc, ab, bc, ca});
    }
    m.indices = std::move(next);
  }
  return m;
}

PrimitiveMesh make_cylinder(int segments) {
  PrimitiveMesh m;
  for (int i = 0; i < segments; ++i) {
    const float a = 2.0f * kPi * static_cast<float>(i) / static_cast<float>(segments);
    const Eigen::Vector3f n(std::cos(a), std::sin(a), 0.0f);
    add_vertex(m, n, n);
    add_vertex(m, n + Eigen::Vector3f::UnitZ(), n);
  }
  const auto s = static_cast<std::uint32_t>(segments);
  for (std::uint32_t i = 0; i < s; ++i) {
    const std::uint32_t a = 2 * i, b = 2 * ((i + 1) % s);
    add_triangle(m, a, b, b + 1);
    add_triangle(m, a, b + 1, a + 1);
  }
  add_cap(m, segments, 0.0f, false);
  add_cap(m, segments, 1.0f, true);
  return m;
}

PrimitiveMesh make_cone(int segments) {
  PrimitiveMesh m;
  const float k = 1.0f / std::sqrt(2.0f);  // slant normal of a cone as high as it is wide
  for (int i = 0; i < segments; ++i) {
    const float a = 2.0f * kPi * static_cast<float>(i) / static_cast<float>(segments);
    const float a_mid = a + kPi / static_cast<float>(segments);
    const Eigen::Vector3f n(k * std::cos(a), k * std::sin(a), k);
    const Eigen::Vector3f n_apex(k * std::cos(a_mid), k * std::sin(a_mid), k);
    add_vertex(m, Eigen::Vector3f(std::cos(a), std::sin(a), 0.0f), n);
    add_vertex(m, Eigen::Vector3f(0.0f, 0.0f, 1.0f), n_apex);
  }
  const auto s = static_cast<std::uint32_t>(segments);
  for (std::uint32_t i = 0; i < s; ++i) add_triangle(m, 2 * i, 2 * ((i + 1) % s), 2 * i + 1);
  add_cap(m, segments, 0.0f, false);
  return m;
}

PlanePatch make_plane_patch(const std::vector<Plane>& planes, std::size_t index,
                            const Bounds& bounds, float grid_step_m) {
  PlanePatch patch;
  const Plane& pl = planes[index];
  patch.plane = pl;
  const Eigen::Vector3f n = pl.normal.normalized();
  Eigen::Vector3f u, v;
  plane_basis(n, u, v);
  // the rectangle of the bounds' corners projected into the plane
  const Eigen::Vector3f origin = n * pl.offset_m;
  float u_min = 1e30f, u_max = -1e30f, v_min = 1e30f, v_max = -1e30f;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3f corner((c & 1) ? bounds.max.x() : bounds.min.x(),
                                 (c & 2) ? bounds.max.y() : bounds.min.y(),
                                 (c & 4) ? bounds.max.z() : bounds.min.z());
    const Eigen::Vector3f d = corner - origin;
    u_min = std::min(u_min, d.dot(u));
    u_max = std::max(u_max, d.dot(u));
    v_min = std::min(v_min, d.dot(v));
    v_max = std::max(v_max, d.dot(v));
  }
  auto at = [&](float a, float b) -> Eigen::Vector3f { return origin + a * u + b * v; };
  patch.polygon = {at(u_min, v_min), at(u_max, v_min), at(u_max, v_max), at(u_min, v_max)};
  // other planes cut it, slightly relaxed so that patches meet without gaps
  std::vector<Plane> cutters;
  for (std::size_t j = 0; j < planes.size(); ++j) {
    if (j == index) continue;
    const Eigen::Vector3f nj = planes[j].normal.normalized();
    if (std::abs(nj.dot(n)) > 0.999f) continue;  // parallel: no edge to cut along
    cutters.push_back(Plane{nj, planes[j].offset_m - 1e-4f});
  }
  for (const Plane& c : cutters) patch.polygon = clip_polygon(patch.polygon, c);
  if (patch.polygon.size() < 3) {
    patch.polygon.clear();
    return patch;
  }
  // grid lines at multiples of the step, clipped like the polygon
  if (grid_step_m > 0.0f) {
    auto add_line = [&](Eigen::Vector3f a, Eigen::Vector3f b) {
      for (const Plane& c : cutters) {
        if (!clip_segment(a, b, c)) return;
      }
      patch.grid.push_back({a, b});
    };
    const auto first_u = static_cast<int>(std::ceil(u_min / grid_step_m));
    const auto last_u = static_cast<int>(std::floor(u_max / grid_step_m));
    for (int k = first_u; k <= last_u; ++k) {
      const float a = static_cast<float>(k) * grid_step_m;
      add_line(at(a, v_min), at(a, v_max));
    }
    const auto first_v = static_cast<int>(std::ceil(v_min / grid_step_m));
    const auto last_v = static_cast<int>(std::floor(v_max / grid_step_m));
    for (int k = first_v; k <= last_v; ++k) {
      const float b = static_cast<float>(k) * grid_step_m;
      add_line(at(u_min, b), at(u_max, b));
    }
  }
  return patch;
}

void vertex_normals(const float* positions, std::size_t vertex_count,
                    const std::uint32_t* triangles, std::size_t triangle_count, float* normals) {
  std::fill(normals, normals + 3 * vertex_count, 0.0f);
  for (std::size_t t = 0; t < triangle_count; ++t) {
    const std::uint32_t ia = triangles[3 * t], ib = triangles[3 * t + 1], ic = triangles[3 * t + 2];
    const Eigen::Map<const Eigen::Vector3f> a(positions + 3 * ia), b(positions + 3 * ib),
        c(positions + 3 * ic);
    const Eigen::Vector3f n = (b - a).cross(c - a);  // length = twice the area: area weighting
    for (const std::uint32_t i : {ia, ib, ic}) Eigen::Map<Eigen::Vector3f>(normals + 3 * i) += n;
  }
  for (std::size_t i = 0; i < vertex_count; ++i) {
    Eigen::Map<Eigen::Vector3f> n(normals + 3 * i);
    const float len = n.norm();
    if (len > 1e-12f) {
      n /= len;
    } else {
      n = Eigen::Vector3f::UnitZ();
    }
  }
}

Eigen::Vector3f displacement_color(float d_m, float scale_m) {
  // blue (0) -> light grey (half) -> red (scale and beyond)
  const float s = std::clamp(scale_m > 0.0f ? d_m / scale_m : 0.0f, 0.0f, 1.0f);
  const Eigen::Vector3f low(0.23f, 0.30f, 0.75f), mid(0.86f, 0.86f, 0.86f),
      high(0.71f, 0.02f, 0.15f);
  if (s < 0.5f) return low + (mid - low) * (2.0f * s);
  return mid + (high - mid) * (2.0f * s - 1.0f);
}

RigidFit best_rigid_fit(const float* from, const float* to, std::size_t count) {
  RigidFit fit;
  if (count == 0) return fit;
  Eigen::Vector3d ca = Eigen::Vector3d::Zero(), cb = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < count; ++i) {
    ca += Eigen::Map<const Eigen::Vector3f>(from + 3 * i).cast<double>();
    cb += Eigen::Map<const Eigen::Vector3f>(to + 3 * i).cast<double>();
  }
  ca /= static_cast<double>(count);
  cb /= static_cast<double>(count);
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();  // cross-covariance of the centred points
  for (std::size_t i = 0; i < count; ++i) {
    h += (Eigen::Map<const Eigen::Vector3f>(from + 3 * i).cast<double>() - ca) *
         (Eigen::Map<const Eigen::Vector3f>(to + 3 * i).cast<double>() - cb).transpose();
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  const Eigen::Matrix3d r = svd.matrixV() * d * svd.matrixU().transpose();
  fit.rotation = r.cast<float>();
  fit.from_centroid = ca.cast<float>();
  fit.to_centroid = cb.cast<float>();
  return fit;
}

}  // namespace teleop::viewer
