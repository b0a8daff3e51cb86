#pragma once
// Small mesh generators for the collision tests (independent of the deformable module).
#include <Eigen/Core>
#include <cmath>
#include <map>
#include <random>
#include <utility>
#include <vector>

namespace teleop::sim::collision::testing {

struct Mesh {
  Eigen::Matrix3Xd x;
  Eigen::Matrix3Xi tris;
};

/// Icosahedron subdivided `level` times, projected onto a sphere; CCW seen from outside.
inline Mesh icosphere(int level, double radius, const Eigen::Vector3d& centre) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0},
                                    {0, -1, t}, {0, 1, t}, {0, -1, -t}, {0, 1, -t},
                                    {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p.normalize();
  std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[static_cast<std::size_t>(a)] + v[static_cast<std::size_t>(b)]).normalized());
      const int id = static_cast<int>(v.size()) - 1;
      mid[key] = id;
      return id;
    };
    std::vector<Eigen::Vector3i> nf;
    for (const auto& tri : f) {
      const int a = midpoint(tri[0], tri[1]);
      const int b = midpoint(tri[1], tri[2]);
      const int c = midpoint(tri[2], tri[0]);
      nf.push_back({tri[0], a, c});
      nf.push_back({tri[1], b, a});
      nf.push_back({tri[2], c, b});
      nf.push_back({a, b, c});
    }
    f = nf;
  }
  Mesh m;
  m.x.resize(3, static_cast<Eigen::Index>(v.size()));
  for (std::size_t i = 0; i < v.size(); ++i) {
    m.x.col(static_cast<Eigen::Index>(i)) = centre + radius * v[i];
  }
  m.tris.resize(3, static_cast<Eigen::Index>(f.size()));
  for (std::size_t i = 0; i < f.size(); ++i) m.tris.col(static_cast<Eigen::Index>(i)) = f[i];
  return m;
}

/// A random soup of `n` triangles in the cube [-1, 1]^3 with edge scale `size`.
inline Mesh random_soup(int n, double size, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Mesh m;
  m.x.resize(3, 3 * n);
  m.tris.resize(3, n);
  for (int t = 0; t < n; ++t) {
    const Eigen::Vector3d c(u(rng), u(rng), u(rng));
    for (int k = 0; k < 3; ++k) {
      m.x.col(3 * t + k) = c + size * Eigen::Vector3d(u(rng), u(rng), u(rng));
      m.tris(k, t) = 3 * t + k;
    }
  }
  return m;
}

/// Axis-aligned closed box mesh (12 triangles, CCW from outside) between lo and hi.
inline Mesh box_mesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  Mesh m;
  m.x.resize(3, 8);
  for (int i = 0; i < 8; ++i) {
    m.x.col(i) = Eigen::Vector3d((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(),
                                 (i & 4) ? hi.z() : lo.z());
  }
  const int f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                        {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  m.tris.resize(3, 12);
  for (int t = 0; t < 12; ++t) m.tris.col(t) = Eigen::Vector3i(f[t][0], f[t][1], f[t][2]);
  return m;
}

}  // namespace teleop::sim::collision::testing
