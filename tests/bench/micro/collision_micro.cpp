// Google Benchmark micro benchmarks of the collision module's hot calls on the level-4
// sphere (5120 triangles): refit, closest point, sphere query, full tip update.
#include <benchmark/benchmark.h>

#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <vector>

#include "common/mesh/tri_mesh.hpp"
#include "server/collision/aabb_tree.hpp"
#include "server/collision/tip_mesh_contact.hpp"

namespace {

namespace tc = teleop::sim::collision;

struct Fixture {
  teleop::mesh::TriMesh mesh;
  Eigen::Matrix3Xd x;
  explicit Fixture(int level) : mesh(teleop::mesh::make_icosphere(level, 0.25, {0, 0, 0})) {
    x = mesh.vertices;
  }
};

void BM_TreeRefit(benchmark::State& st) {
  Fixture f(static_cast<int>(st.range(0)));
  tc::AabbTree tree;
  tree.build(f.x, f.mesh.triangles);
  for (auto _ : st) {
    tree.refit(f.x);
    benchmark::ClobberMemory();
  }
  st.SetLabel(std::to_string(f.mesh.triangles.cols()) + " triangles");
}
BENCHMARK(BM_TreeRefit)->DenseRange(3, 6)->Unit(benchmark::kMicrosecond);

void BM_TreeClosestPoint(benchmark::State& st) {
  Fixture f(static_cast<int>(st.range(0)));
  tc::AabbTree tree;
  tree.build(f.x, f.mesh.triangles);
  tc::MeshClosest mc;
  const Eigen::Vector3d c(0.01, 0.02, 0.301);
  for (auto _ : st) {
    tree.closest_point(c, f.x, std::numeric_limits<double>::infinity(), mc);
    benchmark::DoNotOptimize(mc.distance_m);
  }
}
BENCHMARK(BM_TreeClosestPoint)->DenseRange(3, 6)->Unit(benchmark::kMicrosecond);

void BM_TreeSphereQuery(benchmark::State& st) {
  Fixture f(4);
  tc::AabbTree tree;
  tree.build(f.x, f.mesh.triangles);
  std::vector<int> hits;
  hits.reserve(static_cast<std::size_t>(f.mesh.triangles.cols()));
  const Eigen::Vector3d c(0.01, 0.02, 0.29);
  for (auto _ : st) {
    tree.query_sphere(c, 0.05, f.x, hits);
    benchmark::DoNotOptimize(hits.data());
  }
}
BENCHMARK(BM_TreeSphereQuery)->Unit(benchmark::kMicrosecond);

void BM_TipUpdateInContact(benchmark::State& st) {
  Fixture f(4);
  tc::TipMeshContact contact;
  contact.reset(f.x, f.mesh.triangles);
  Eigen::Matrix3Xd fn = Eigen::Matrix3Xd::Zero(3, f.x.cols());
  const Eigen::Vector3d p(0.0, 0.0, 0.296), q(0.0, 0.0, 0.295);
  for (auto _ : st) {
    auto r = contact.update(f.x, p, q, 0.05, Eigen::Vector3d(0, 0, -1), 1e-3, fn);
    benchmark::DoNotOptimize(r.force_on_tip_n);
  }
}
BENCHMARK(BM_TipUpdateInContact)->Unit(benchmark::kMicrosecond);

}  // namespace
