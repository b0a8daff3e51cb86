// Exact primitives against brute-force references.
#include "server/collision/geometry.hpp"

#include <gtest/gtest.h>

#include <random>

#include "server/collision/surface_topology.hpp"
#include "tests/unit/server/collision/test_meshes.hpp"

namespace tc = teleop::sim::collision;
using Eigen::Vector3d;

namespace {

// distance to a triangle by dense sampling of its barycentric domain (upper bound)
double sampled_distance(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c,
                        int n) {
  double best = 1e300;
  for (int i = 0; i <= n; ++i) {
    for (int j = 0; i + j <= n; ++j) {
      const double u = static_cast<double>(i) / n;
      const double v = static_cast<double>(j) / n;
      best = std::min(best, (p - (a + u * (b - a) + v * (c - a))).norm());
    }
  }
  return best;
}

}  // namespace

TEST(Geometry, ClosestPointMatchesSampling) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 300; ++trial) {
    const Vector3d a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng));
    const Vector3d p = 2.0 * Vector3d(u(rng), u(rng), u(rng));
    const tc::TriClosest r = tc::closest_point_on_triangle(p, a, b, c);
    const double exact = std::sqrt(r.distance_sq);
    const double sampled = sampled_distance(p, a, b, c, 200);
    // the exact distance is never above the sampled one and within the sampling resolution
    EXPECT_LE(exact, sampled + 1e-12);
    EXPECT_NEAR(exact, sampled, 0.02);
    // barycentric weights reproduce the point
    EXPECT_NEAR((r.bary[0] * a + r.bary[1] * b + r.bary[2] * c - r.point).norm(), 0.0, 1e-12);
    EXPECT_NEAR(r.bary.sum(), 1.0, 1e-12);
    EXPECT_GE(r.bary.minCoeff(), -1e-12);
  }
}

TEST(Geometry, ClosestPointDegenerateTriangle) {
  const Vector3d a(0, 0, 0), b(1, 0, 0), c(2, 0, 0);  // collinear
  const tc::TriClosest r = tc::closest_point_on_triangle(Vector3d(1.5, 1.0, 0.0), a, b, c);
  EXPECT_NEAR(std::sqrt(r.distance_sq), 1.0, 1e-12);
  EXPECT_NEAR(r.point.x(), 1.5, 1e-12);
}

TEST(Geometry, SegmentTriangleEquation8) {
  const Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  // straight through the interior
  tc::SegmentHit h =
      tc::intersect_segment_triangle(Vector3d(0.2, 0.3, 1.0), Vector3d(0.2, 0.3, -1.0), a, b, c);
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.w, 0.5, 1e-15);
  EXPECT_NEAR(h.u, 0.2, 1e-15);
  EXPECT_NEAR(h.v, 0.3, 1e-15);
  EXPECT_NEAR((h.point - Vector3d(0.2, 0.3, 0.0)).norm(), 0.0, 1e-15);
  // stops short, passes beside, runs parallel
  EXPECT_FALSE(
      tc::intersect_segment_triangle(Vector3d(0.2, 0.3, 1.0), Vector3d(0.2, 0.3, 0.1), a, b, c)
          .hit);
  EXPECT_FALSE(
      tc::intersect_segment_triangle(Vector3d(0.8, 0.8, 1.0), Vector3d(0.8, 0.8, -1.0), a, b, c)
          .hit);
  EXPECT_FALSE(
      tc::intersect_segment_triangle(Vector3d(0.1, 0.1, 0.0), Vector3d(0.5, 0.1, 0.0), a, b, c)
          .hit);
  // random segments against the sign change of the plane distance plus the inside test
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 2000; ++i) {
    const Vector3d p(u(rng), u(rng), u(rng)), q(u(rng), u(rng), u(rng));
    const tc::SegmentHit s = tc::intersect_segment_triangle(p, q, a, b, c);
    bool expect = false;
    if (p.z() * q.z() < 0.0) {
      const double w = p.z() / (p.z() - q.z());
      const Vector3d x = p + w * (q - p);
      expect = x.x() >= 0 && x.y() >= 0 && x.x() + x.y() <= 1;
    }
    EXPECT_EQ(s.hit, expect) << "p " << p.transpose() << " q " << q.transpose();
  }
}

TEST(Geometry, WindingNumberOfClosedMeshes) {
  const auto s = tc::testing::icosphere(2, 0.25, Vector3d(0.1, 0.2, 0.3));
  EXPECT_NEAR(tc::winding_number(Vector3d(0.1, 0.2, 0.3), s.x, s.tris), 1.0, 1e-9);
  EXPECT_NEAR(tc::winding_number(Vector3d(0.1, 0.2, 0.5), s.x, s.tris), 1.0, 1e-9);
  EXPECT_NEAR(tc::winding_number(Vector3d(0.1, 0.2, 0.6), s.x, s.tris), 0.0, 1e-9);
  const auto b = tc::testing::box_mesh(Vector3d(0, 0, 0), Vector3d(1, 2, 3));
  EXPECT_NEAR(tc::winding_number(Vector3d(0.5, 1, 1.5), b.x, b.tris), 1.0, 1e-9);
  EXPECT_NEAR(tc::winding_number(Vector3d(1.5, 1, 1.5), b.x, b.tris), 0.0, 1e-9);
  tc::SurfaceTopology topo;
  topo.build(b.tris, 8);
  EXPECT_TRUE(topo.closed());
  topo.build(s.tris, static_cast<int>(s.x.cols()));
  EXPECT_TRUE(topo.closed());
}

TEST(Geometry, SegmentAabbSlab) {
  const Vector3d lo(0, 0, 0), hi(1, 1, 1);
  EXPECT_TRUE(
      tc::segment_intersects_aabb(Vector3d(-1, 0.5, 0.5), Vector3d(2, 0.5, 0.5), lo, hi, 0));
  EXPECT_FALSE(
      tc::segment_intersects_aabb(Vector3d(-1, 1.5, 0.5), Vector3d(2, 1.5, 0.5), lo, hi, 0));
  EXPECT_TRUE(
      tc::segment_intersects_aabb(Vector3d(-1, 1.5, 0.5), Vector3d(2, 1.5, 0.5), lo, hi, 0.6));
  EXPECT_FALSE(
      tc::segment_intersects_aabb(Vector3d(-1, 0.5, 0.5), Vector3d(-0.5, 0.5, 0.5), lo, hi, 0));
}
