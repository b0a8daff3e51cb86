// teleop_bench collision --out DIR: per-step cost of keeping collision detection current on a
// deforming icosphere (levels 3-6), for the tip near the surface:
//   tree_refit        AabbTree::rebuild_if_degraded (O(n) refit, rebuild when degraded)
//   tree_query        closest point + exact sphere query for the tip (r = 0.05 m)
//   tree_refit_query  both: what one physics step pays
//   tip_update        TipMeshContact::update in contact (refit + detection + response)
//   brute_query       the same queries by looping over every triangle
//   fcl_rebuild       FCL 0.7 BVHModel<OBBRSS> rebuilt each step + sphere distance
//   fcl_refit         FCL's in-place update (OBBRSS refit) + sphere distance
// Medians and p99 go to collision_bench.csv; the largest distance error of each method
// against brute force goes in max_error_m.
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision_object.h>
#include <fcl/narrowphase/distance.h>

#include <Eigen/Core>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "common/mesh/tri_mesh.hpp"
#include "common/util/csv.hpp"
#include "common/util/registry.hpp"
#include "common/util/stats.hpp"
#include "server/collision/aabb_tree.hpp"
#include "server/collision/tip_mesh_contact.hpp"

namespace {

namespace tc = teleop::sim::collision;
using Clock = std::chrono::steady_clock;

struct Scene {
  Eigen::Matrix3Xd rest, x, normal;
  Eigen::Matrix3Xi tris;
  // a travelling ripple on the surface (amplitude 5 mm) and a tip circling over the top
  void deform(int step) {
    const double t = step * 1e-3;
    for (int i = 0; i < rest.cols(); ++i) {
      const double ph = 12.0 * normal(0, i) + 7.0 * normal(1, i);
      x.col(i) = rest.col(i) + 0.005 * std::sin(2.0 * M_PI * 3.0 * t + ph) * normal.col(i);
    }
  }
  static Eigen::Vector3d tip(int step, double gap) {
    const double t = step * 1e-3;
    return Eigen::Vector3d(0.03 * std::cos(2.0 * M_PI * t), 0.03 * std::sin(2.0 * M_PI * t),
                           0.25 + 0.05 + gap);
  }
};

double brute_distance(const Eigen::Vector3d& p, const Scene& s, std::vector<int>& hits, double r) {
  double best = std::numeric_limits<double>::infinity();
  hits.clear();
  for (int t = 0; t < s.tris.cols(); ++t) {
    const auto c = tc::closest_point_on_triangle(p, s.x.col(s.tris(0, t)), s.x.col(s.tris(1, t)),
                                                 s.x.col(s.tris(2, t)));
    best = std::min(best, c.distance_sq);
    if (c.distance_sq <= r * r) hits.push_back(t);
  }
  return std::sqrt(best);
}

/// One level's rows: a CSV row and a line on stdout per method.
struct Emitter {
  teleop::CsvWriter& csv;
  int level = 0, tri_count = 0;
  void operator()(const char* method, std::vector<double>& us, double err) const {
    const teleop::Summary sm = teleop::summarize(us);
    csv.row_text({std::to_string(level), std::to_string(tri_count), method,
                  std::to_string(us.size()), teleop::format_number(sm.p50),
                  teleop::format_number(sm.p99), teleop::format_number(sm.mean),
                  teleop::format_number(err)});
    std::printf("level %d (%5d tris) %-17s median %9.2f us  p99 %9.2f us  max err %.2e m\n", level,
                tri_count, method, sm.p50, sm.p99, err);
  }
};

double time_us(const std::function<void()>& f) {
  const auto t0 = Clock::now();
  f();
  return std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
}

/// Our tree: refit, query, both, against brute force (every fifth step), tip 1 mm above.
void bench_tree(Scene& s, int n_fast, double r, const Emitter& emit) {
  const int tri_count = static_cast<int>(s.tris.cols());
  tc::AabbTree tree;
  tree.build(s.x, s.tris);
  std::vector<int> hits, bhits;
  hits.reserve(static_cast<std::size_t>(tri_count));
  bhits.reserve(static_cast<std::size_t>(tri_count));
  std::vector<double> t_refit, t_query, t_both, t_brute;
  double err_tree = 0.0;
  for (int i = 0; i < n_fast; ++i) {
    s.deform(i);
    const Eigen::Vector3d c = Scene::tip(i, 0.001);
    tc::MeshClosest mc;
    const double a = time_us([&] { tree.rebuild_if_degraded(s.x); });
    const double b = time_us([&] {
      tree.closest_point(c, s.x, std::numeric_limits<double>::infinity(), mc);
      tree.query_sphere(c, r, s.x, hits);
    });
    t_refit.push_back(a);
    t_query.push_back(b);
    t_both.push_back(a + b);
    if (i % 5 == 0) {
      double bd = 0.0;
      t_brute.push_back(time_us([&] { bd = brute_distance(c, s, bhits, r); }));
      err_tree = std::max(err_tree, std::abs(bd - mc.distance_m));
      if (bhits.size() != hits.size()) err_tree = std::max(err_tree, 1.0);  // hit sets differ
    }
  }
  emit("tree_refit", t_refit, 0.0);
  emit("tree_query", t_query, err_tree);
  emit("tree_refit_query", t_both, err_tree);
  emit("brute_query", t_brute, 0.0);
}

/// The whole tip contact update, tip pressing 5 mm into the rippling surface.
void bench_tip_update(Scene& s, int n_fast, double r, const Emitter& emit) {
  tc::TipMeshContact contact;
  contact.reset(s.x, s.tris);
  Eigen::Matrix3Xd fn = Eigen::Matrix3Xd::Zero(3, s.x.cols());
  std::vector<double> t_up;
  Eigen::Vector3d prev = Scene::tip(0, -0.005);
  for (int i = 0; i < n_fast; ++i) {
    s.deform(i);
    const Eigen::Vector3d c = Scene::tip(i, -0.005);
    fn.setZero();
    t_up.push_back(time_us([&] { contact.update(s.x, prev, c, r, (c - prev) / 1e-3, 1e-3, fn); }));
    prev = c;
  }
  emit("tip_update", t_up, 0.0);
}

/// The distance from an FCL model to the tip sphere.
double fcl_distance(fcl::CollisionObjectd& obj, fcl::CollisionObjectd& tip_obj) {
  fcl::DistanceRequestd req;
  fcl::DistanceResultd res;
  fcl::distance(&obj, &tip_obj, req, res);
  return res.min_distance;
}

/// FCL: rebuild an OBBRSS BVHModel every step, and refit one in place.
void bench_fcl(Scene& s, int n_slow, double r, const Emitter& emit) {
  const int tri_count = static_cast<int>(s.tris.cols());
  std::vector<int> bhits;
  bhits.reserve(static_cast<std::size_t>(tri_count));
  std::vector<fcl::Vector3d> pts(static_cast<std::size_t>(s.x.cols()));
  std::vector<fcl::Triangle> ftris;
  for (int t = 0; t < tri_count; ++t) {
    ftris.emplace_back(s.tris(0, t), s.tris(1, t), s.tris(2, t));
  }
  auto sphere = std::make_shared<fcl::Sphered>(r);
  std::vector<double> t_rebuild, t_frefit;
  double err_rebuild = 0.0, err_refit = 0.0;
  auto refit_model = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
  for (int i = 0; i < s.x.cols(); ++i) pts[static_cast<std::size_t>(i)] = s.x.col(i);
  refit_model->beginModel(tri_count, static_cast<int>(s.x.cols()));
  refit_model->addSubModel(pts, ftris);
  refit_model->endModel();
  fcl::CollisionObjectd refit_obj(refit_model);
  for (int i = 0; i < n_slow; ++i) {
    s.deform(i * 7);
    const Eigen::Vector3d c = Scene::tip(i * 7, 0.001);
    for (int v = 0; v < s.x.cols(); ++v) pts[static_cast<std::size_t>(v)] = s.x.col(v);
    fcl::Transform3d tf = fcl::Transform3d::Identity();
    tf.translation() = c;
    fcl::CollisionObjectd tip_obj(sphere, tf);
    tip_obj.computeAABB();
    double d_rebuild = 0.0, d_refit = 0.0;
    t_rebuild.push_back(time_us([&] {
      auto model = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
      model->beginModel(tri_count, static_cast<int>(s.x.cols()));
      model->addSubModel(pts, ftris);
      model->endModel();
      fcl::CollisionObjectd obj(model);
      obj.computeAABB();
      d_rebuild = fcl_distance(obj, tip_obj);
    }));
    t_frefit.push_back(time_us([&] {
      refit_model->beginUpdateModel();
      refit_model->updateSubModel(pts);
      refit_model->endUpdateModel(true, true);
      refit_obj.computeAABB();  // stale outer box otherwise
      d_refit = fcl_distance(refit_obj, tip_obj);
    }));
    const double bd = brute_distance(c, s, bhits, r) - r;
    err_rebuild = std::max(err_rebuild, std::abs(d_rebuild - bd));
    err_refit = std::max(err_refit, std::abs(d_refit - bd));
  }
  emit("fcl_rebuild", t_rebuild, err_rebuild);
  emit("fcl_refit", t_frefit, err_refit);
}

int run_collision_bench(const teleop::CommandArgs& args) {
  std::filesystem::create_directories(args.out_dir);
  teleop::CsvWriter csv(
      (args.out_dir / "collision_bench.csv").string(),
      {"level", "triangles", "method", "samples", "median_us", "p99_us", "mean_us", "max_error_m"});
  const std::vector<int> levels =
      args.quick ? std::vector<int>{3, 4} : std::vector<int>{3, 4, 5, 6};
  const double r = 0.05;
  teleop::Progress progress("collision", static_cast<double>(levels.size()), "levels");
  for (const int level : levels) {
    Scene s;
    const auto mesh = teleop::mesh::make_icosphere(level, 0.25, Eigen::Vector3d::Zero());
    s.rest = mesh.vertices;
    s.x = s.rest;
    s.normal = s.rest.colwise().normalized();
    s.tris = mesh.triangles;
    int n_fast = level <= 4 ? 3000 : (level == 5 ? 800 : 200);
    int n_slow = level <= 4 ? 200 : (level == 5 ? 40 : 12);
    if (args.quick) {
      n_fast /= 10;
      n_slow = std::max(5, n_slow / 10);
    }
    const Emitter emit{csv, level, static_cast<int>(s.tris.cols())};
    // in this order: each starts from the surface the one before left
    bench_tree(s, n_fast, r, emit);
    bench_tip_update(s, n_fast, r, emit);
    bench_fcl(s, n_slow, r, emit);
    progress.add();
  }
  progress.finish();
  csv.flush();
  if (!args.no_chart) teleop::run_chart_script("collision_bench.py", {args.out_dir.string()});
  return 0;
}

}  // namespace

TELEOP_REGISTER_COMMAND(bench, "collision",
                        "AABB tree refit + tip query vs brute force vs FCL BVH rebuild/refit "
                        "on a deforming icosphere, levels 3-6 (median, p99)",
                        run_collision_bench);
