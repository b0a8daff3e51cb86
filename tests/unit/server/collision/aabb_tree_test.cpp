// The AABB tree agrees with brute force on random meshes and poses, after refits and rebuilds.
#include "server/collision/aabb_tree.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "tests/support/alloc_counter.hpp"
#include "tests/unit/server/collision/test_meshes.hpp"

namespace tc = teleop::sim::collision;
using Eigen::Vector3d;

namespace {

std::vector<int> brute_sphere(const tc::testing::Mesh& m, const Vector3d& c, double r) {
  std::vector<int> hits;
  for (int t = 0; t < m.tris.cols(); ++t) {
    const auto cp = tc::closest_point_on_triangle(c, m.x.col(m.tris(0, t)), m.x.col(m.tris(1, t)),
                                                  m.x.col(m.tris(2, t)));
    if (cp.distance_sq <= r * r) hits.push_back(t);
  }
  return hits;
}

double brute_distance(const tc::testing::Mesh& m, const Vector3d& p) {
  double best = 1e300;
  for (int t = 0; t < m.tris.cols(); ++t) {
    best =
        std::min(best, tc::closest_point_on_triangle(p, m.x.col(m.tris(0, t)),
                                                     m.x.col(m.tris(1, t)), m.x.col(m.tris(2, t)))
                           .distance_sq);
  }
  return std::sqrt(best);
}

std::vector<int> brute_segment(const tc::testing::Mesh& m, const Vector3d& p, const Vector3d& q) {
  std::vector<int> hits;
  for (int t = 0; t < m.tris.cols(); ++t) {
    if (tc::intersect_segment_triangle(p, q, m.x.col(m.tris(0, t)), m.x.col(m.tris(1, t)),
                                       m.x.col(m.tris(2, t)))
            .hit) {
      hits.push_back(t);
    }
  }
  return hits;
}

void check_against_brute(const tc::AabbTree& tree, const tc::testing::Mesh& m, std::mt19937& rng,
                         int queries) {
  std::uniform_real_distribution<double> u(-1.2, 1.2);
  std::uniform_real_distribution<double> ur(0.0, 0.4);
  std::vector<int> hits;
  hits.reserve(static_cast<std::size_t>(m.tris.cols()));
  for (int q = 0; q < queries; ++q) {
    const Vector3d c(u(rng), u(rng), u(rng));
    const double r = ur(rng);
    tree.query_sphere(c, r, m.x, hits);
    std::sort(hits.begin(), hits.end());
    ASSERT_EQ(hits, brute_sphere(m, c, r)) << "sphere query " << q;

    tc::MeshClosest mc;
    ASSERT_TRUE(tree.closest_point(c, m.x, std::numeric_limits<double>::infinity(), mc));
    const double bd = brute_distance(m, c);
    EXPECT_NEAR(mc.distance_m, bd, 1e-9);
    EXPECT_NEAR((mc.point - c).norm(), bd, 1e-9);
    // bounded search finds it only when within the bound
    tc::MeshClosest mb;
    EXPECT_EQ(tree.closest_point(c, m.x, bd * 0.999, mb), false);
    EXPECT_TRUE(tree.closest_point(c, m.x, bd * 1.001 + 1e-12, mb));

    const Vector3d p0(u(rng), u(rng), u(rng)), p1(u(rng), u(rng), u(rng));
    tree.query_segment(p0, p1, m.x, hits);
    std::sort(hits.begin(), hits.end());
    const auto bs = brute_segment(m, p0, p1);
    ASSERT_EQ(hits, bs) << "segment query " << q;
    tc::MeshSegmentHit first;
    const bool any = tree.first_segment_hit(p0, p1, m.x, first);
    ASSERT_EQ(any, !bs.empty());
    if (any) {
      double wmin = 2.0;
      for (int t : bs) {
        wmin = std::min(wmin,
                        tc::intersect_segment_triangle(p0, p1, m.x.col(m.tris(0, t)),
                                                       m.x.col(m.tris(1, t)), m.x.col(m.tris(2, t)))
                            .w);
      }
      EXPECT_NEAR(first.w, wmin, 1e-12);
    }
  }
}

}  // namespace

TEST(AabbTree, RandomSoupsAgreeWithBruteForce) {
  std::mt19937 rng(42);
  for (int leaf : {1, 2, 4, 8}) {
    for (int n : {1, 7, 100, 1000}) {
      auto m = tc::testing::random_soup(n, 0.15, rng);
      tc::AabbTree tree(tc::AabbTree::Options{leaf, 1.5});
      tree.build(m.x, m.tris);
      EXPECT_EQ(tree.triangle_count(), n);
      check_against_brute(tree, m, rng, 60);
    }
  }
}

TEST(AabbTree, IcosphereAgreesAfterDeformationRefitAndRebuild) {
  std::mt19937 rng(5);
  auto m = tc::testing::icosphere(3, 0.8, Vector3d::Zero());
  tc::AabbTree tree;
  tree.build(m.x, m.tris);
  EXPECT_NEAR(tree.quality_ratio(), 1.0, 1e-12);
  check_against_brute(tree, m, rng, 60);
  // deform: random displacement field, refit only (boxes must still be exact)
  std::normal_distribution<double> g(0.0, 0.05);
  for (int i = 0; i < m.x.cols(); ++i) m.x.col(i) += Vector3d(g(rng), g(rng), g(rng));
  tree.refit(m.x);
  check_against_brute(tree, m, rng, 60);
  // scramble the mesh heavily: the quality degrades and a rebuild is triggered
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < m.x.cols(); ++i) m.x.col(i) = Vector3d(u(rng), u(rng), u(rng));
  const bool rebuilt = tree.rebuild_if_degraded(m.x);
  EXPECT_TRUE(rebuilt);
  EXPECT_EQ(tree.rebuild_count(), 1u);
  EXPECT_NEAR(tree.quality_ratio(), 1.0, 1e-12);
  check_against_brute(tree, m, rng, 40);
  // a rigid translation keeps the quality: no rebuild
  m.x.colwise() += Vector3d(0.3, 0.0, 0.0);
  EXPECT_FALSE(tree.rebuild_if_degraded(m.x));
  check_against_brute(tree, m, rng, 20);
}

TEST(AabbTree, BoxesContainTheirTriangles) {
  auto m = tc::testing::icosphere(2, 0.25, Vector3d(1, 2, 3));
  tc::AabbTree tree;
  tree.build(m.x, m.tris);
  const tc::Aabb root = tree.root_box();
  EXPECT_NEAR((root.lo - Vector3d(0.75, 1.75, 2.75)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((root.hi - Vector3d(1.25, 2.25, 3.25)).norm(), 0.0, 1e-12);
  // a balanced median split: depth about log2(T / leaf) + 1
  EXPECT_LE(tree.depth(), 12);
  std::vector<int> hits;
  tree.query_aabb(root, hits);
  EXPECT_EQ(static_cast<int>(hits.size()), tree.triangle_count());
}

TEST(AabbTree, RefitRebuildAndQueriesAllocateNothing) {
  auto m = tc::testing::icosphere(4, 0.25, Vector3d::Zero());
  tc::AabbTree tree;
  tree.build(m.x, m.tris);
  std::vector<int> hits;
  hits.reserve(static_cast<std::size_t>(m.tris.cols()));
  tc::MeshClosest mc;
  tc::MeshSegmentHit sh;
  teleop::test::NoAllocScope scope;
  m.x *= 1.01;
  tree.refit(m.x);
  tree.rebuild(m.x);
  tree.rebuild_if_degraded(m.x);
  tree.query_sphere(Vector3d(0.3, 0, 0), 0.1, m.x, hits);
  tree.query_segment(Vector3d(0.5, 0, 0), Vector3d(-0.5, 0, 0), m.x, hits);
  tree.first_segment_hit(Vector3d(0.5, 0, 0), Vector3d(-0.5, 0, 0), m.x, sh);
  tree.closest_point(Vector3d(0.1, 0.2, 0.3), m.x, 1e9, mc);
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_FALSE(hits.empty());
}
