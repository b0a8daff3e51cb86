// teleop_bench growth --out DIR [--quick] [--no-chart] [--rounds N]
// How the cost grows with the mesh: the deformable step against the node count (icosphere
// levels 2-6) and the tip-mesh collision query against the triangle count, with the exponent b
// of cost = a n^b fitted by least squares on log(cost) against log(n).
//
// Deformable: one step of a body disturbed by a 5 mm bump (zero gravity, never sleeping), at a
// step inside its stability limit (dt = min(1 ms, 0.9 x stable step); implicit Euler at 1 ms),
// single steps (no sub-stepping), per model/integrator/kernel below.
// Collision (server/collision/aabb_tree): a rippling icosphere (5 mm travelling wave) and a tip
// sphere (r = 0.05 m) circling 1 mm above the top: tree_refit (refit, rebuild when degraded:
// O(n) by construction), tree_query (closest point + sphere overlap query, what grows with the
// tree depth), tree_refit_query (both: what a physics step pays).
// Interleaved: each round runs every (series, level) once in rotating order; samples pooled.
// Writes DIR/growth.csv (series, kind, level, n, median, p99), DIR/growth_fit.csv (series,
// exponent, prefactor, r2), chart DIR/growth.png (tests/charts/growth.py).
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "common/mesh/tri_mesh.hpp"
#include "common/util/csv.hpp"
#include "common/util/registry.hpp"
#include "common/util/stats.hpp"
#include "server/collision/aabb_tree.hpp"
#include "server/deformable/deformable.hpp"

namespace {

namespace dm = teleop::sim::deformable;
namespace tc = teleop::sim::collision;
using Clock = std::chrono::steady_clock;

struct Series {
  std::string name;
  std::string kind;  // "deformable" (n = nodes) or "collision" (n = triangles)
  dm::ModelKind model = dm::ModelKind::kMassSpring;
  dm::IntegratorKind integrator = dm::IntegratorKind::kSymplecticEuler;
  dm::KernelKind kernel = dm::KernelKind::kScalar;
  int max_level = 6;
};

/// Time budget per (series, level) and round: enough samples, bounded wall time.
int sample_count(double approx_us, bool quick) {
  const double budget_us = quick ? 2e4 : 4e5;
  return std::clamp(static_cast<int>(budget_us / std::max(approx_us, 0.1)), 8, 3000);
}

std::vector<double> time_deformable(const Series& s, int level, bool quick) {
  dm::DeformableParams p;
  p.model = s.model;
  p.integrator = s.integrator;
  p.kernel = s.kernel;
  p.level = level;
  p.centre_m.setZero();
  p.gravity_mps2.setZero();
  if (s.model != dm::ModelKind::kMassSpring) p.radial_stiffness_n_per_m3 = 0.0;
  p.sleep_time_s = 1e9;
  p.max_substeps = 1;
  const dm::DeformableModel m = dm::make_model(dm::make_mesh_for(p), p);
  dm::DeformableState st = dm::make_state(m);
  const Eigen::Vector3d axis = m.mesh.vertices.col(5).normalized();
  for (int i = 0; i < m.node_count; ++i) {  // the bump of teleop_bench deformable
    const Eigen::Vector3d u = m.mesh.vertices.col(i).normalized();
    const double th = std::acos(std::clamp(u.dot(axis), -1.0, 1.0)), hw = M_PI / 6.0;
    if (th < hw) st.x.col(i) += 0.005 * std::pow(std::cos(0.5 * M_PI * th / hw), 2) * u;
  }
  const double dt = s.integrator == dm::IntegratorKind::kImplicitEuler
                        ? 1e-3
                        : std::min(1e-3, 0.9 * m.stable_step_s);
  // a guess of the cost from the node count, refined after the first steps
  std::vector<double> us;
  int n = 8;
  for (int k = 0; k < n; ++k) {
    const auto t0 = Clock::now();
    dm::step(m, st, dt, nullptr);
    us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
    if (k == 2) n = sample_count(teleop::percentile(us, 50.0), quick);
  }
  return us;
}

struct Ripple {
  Eigen::Matrix3Xd rest, x, normal;
  Eigen::Matrix3Xi tris;
  void deform(int step) {
    const double t = step * 1e-3;
    for (int i = 0; i < rest.cols(); ++i) {
      const double ph = 12.0 * normal(0, i) + 7.0 * normal(1, i);
      x.col(i) = rest.col(i) + 0.005 * std::sin(2.0 * M_PI * 3.0 * t + ph) * normal.col(i);
    }
  }
};

/// {refit, query, refit + query} samples.
std::array<std::vector<double>, 3> time_collision(int level, bool quick) {
  Ripple s;
  const auto mesh = teleop::mesh::make_icosphere(level, 0.25, Eigen::Vector3d::Zero());
  s.rest = mesh.vertices;
  s.x = s.rest;
  s.normal = s.rest.colwise().normalized();
  s.tris = mesh.triangles;
  tc::AabbTree tree;
  tree.build(s.x, s.tris);
  std::vector<int> hits;
  hits.reserve(static_cast<std::size_t>(s.tris.cols()));
  std::array<std::vector<double>, 3> out;
  int n = 8;
  for (int i = 0; i < n; ++i) {
    s.deform(i);
    const double t = i * 1e-3;
    const Eigen::Vector3d c(0.03 * std::cos(2.0 * M_PI * t), 0.03 * std::sin(2.0 * M_PI * t),
                            0.25 + 0.05 + 0.001);
    tc::MeshClosest mc;
    const auto t0 = Clock::now();
    tree.rebuild_if_degraded(s.x);
    const auto t1 = Clock::now();
    tree.closest_point(c, s.x, std::numeric_limits<double>::infinity(), mc);
    tree.query_sphere(c, 0.05, s.x, hits);
    const auto t2 = Clock::now();
    out[0].push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    out[1].push_back(std::chrono::duration<double, std::micro>(t2 - t1).count());
    out[2].push_back(std::chrono::duration<double, std::micro>(t2 - t0).count());
    if (i == 2) n = sample_count(teleop::percentile(out[2], 50.0), quick);
  }
  return out;
}

/// Least squares of log(y) = log(a) + b log(n): {b, a, r^2}.
std::array<double, 3> fit_power(const std::vector<double>& n, const std::vector<double>& y) {
  const std::size_t k = n.size();
  double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
  for (std::size_t i = 0; i < k; ++i) {
    const double lx = std::log(n[i]), ly = std::log(y[i]);
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
    syy += ly * ly;
  }
  const double kk = static_cast<double>(k);
  const double b = (kk * sxy - sx * sy) / (kk * sxx - sx * sx);
  const double la = (sy - b * sx) / kk;
  const double ss_tot = syy - sy * sy / kk;
  double ss_res = 0;
  for (std::size_t i = 0; i < k; ++i) {
    const double d = std::log(y[i]) - (la + b * std::log(n[i]));
    ss_res += d * d;
  }
  return {b, std::exp(la), ss_tot > 0 ? 1.0 - ss_res / ss_tot : 1.0};
}

/// The series measured: the deformable models and integrators, and the collision tree.
std::vector<Series> growth_series() {
  return {
      {"mass_spring symplectic scalar", "deformable", dm::ModelKind::kMassSpring,
       dm::IntegratorKind::kSymplecticEuler, dm::KernelKind::kScalar, 6},
      {"mass_spring symplectic simd", "deformable", dm::ModelKind::kMassSpring,
       dm::IntegratorKind::kSymplecticEuler, dm::KernelKind::kSimd, 6},
      {"navier_linear symplectic", "deformable", dm::ModelKind::kNavierLinear,
       dm::IntegratorKind::kSymplecticEuler, dm::KernelKind::kScalar, 6},
      {"navier_corotational symplectic", "deformable", dm::ModelKind::kNavierCorotational,
       dm::IntegratorKind::kSymplecticEuler, dm::KernelKind::kScalar, 6},
      {"mass_spring implicit (1 ms)", "deformable", dm::ModelKind::kMassSpring,
       dm::IntegratorKind::kImplicitEuler, dm::KernelKind::kScalar, 6},
      {"collision tree_refit", "collision", {}, {}, {}, 6},
      {"collision tree_query", "collision", {}, {}, {}, 6},
      {"collision tree_refit_query", "collision", {}, {}, {}, 6},
  };
}

/// Step times [us] per series and level.
using Samples = std::vector<std::vector<std::vector<double>>>;

/// Every (series, level) job timed `rounds` times, the job order rotated each round; one
/// collision job fills the three collision series.
Samples collect_samples(const std::vector<Series>& series, int min_level, int top, int rounds,
                        bool quick) {
  struct Job {
    std::size_t series;  // first series of a collision job fills all three
    int level;
  };
  std::vector<Job> jobs;
  for (std::size_t i = 0; i < series.size(); ++i) {
    if (series[i].kind == "collision" && series[i].name != "collision tree_refit") continue;
    for (int l = min_level; l <= std::min(top, series[i].max_level); ++l) jobs.push_back({i, l});
  }
  Samples samples(series.size(), std::vector<std::vector<double>>(7));
  teleop::Progress progress("growth", static_cast<double>(rounds) * jobs.size(), "jobs");
  for (int r = 0; r < rounds; ++r) {
    for (std::size_t j = 0; j < jobs.size(); ++j) {
      const Job& job = jobs[(j + static_cast<std::size_t>(r) * 3) % jobs.size()];
      const Series& s = series[job.series];
      auto& dst = samples[job.series][static_cast<std::size_t>(job.level)];
      if (s.kind == "deformable") {
        const auto us = time_deformable(s, job.level, quick);
        dst.insert(dst.end(), us.begin(), us.end());
      } else {
        const auto us = time_collision(job.level, quick);
        for (std::size_t k = 0; k < 3; ++k) {
          auto& d = samples[job.series + k][static_cast<std::size_t>(job.level)];
          d.insert(d.end(), us[k].begin(), us[k].end());
        }
      }
      progress.add();
    }
  }
  progress.finish();
  return samples;
}

/// growth.csv (median and p99 per series and level) and growth_fit.csv (the power law of each
/// series measured at two levels or more), echoed on stdout.
void write_growth(const std::filesystem::path& out_dir, const std::vector<Series>& series,
                  const Samples& samples, int min_level, int top) {
  teleop::CsvWriter csv((out_dir / "growth.csv").string(),
                        {"series", "kind", "level", "n", "samples", "median_us", "p99_us"});
  teleop::CsvWriter fit_csv((out_dir / "growth_fit.csv").string(),
                            {"series", "kind", "exponent", "prefactor_us", "r2", "levels"});
  for (std::size_t i = 0; i < series.size(); ++i) {
    const Series& s = series[i];
    std::vector<double> ns, meds;
    for (int l = min_level; l <= std::min(top, s.max_level); ++l) {
      const auto& us = samples[i][static_cast<std::size_t>(l)];
      if (us.empty()) continue;
      const double n =
          s.kind == "deformable" ? 10.0 * std::pow(4.0, l) + 2.0 : 20.0 * std::pow(4.0, l);
      const double med = teleop::percentile(us, 50.0), p99 = teleop::percentile(us, 99.0);
      ns.push_back(n);
      meds.push_back(med);
      csv.row_text({s.name, s.kind, std::to_string(l), teleop::format_number(n),
                    std::to_string(us.size()), teleop::format_number(med),
                    teleop::format_number(p99)});
      std::printf("%-32s level %d n %7.0f  median %10.2f us  p99 %10.2f us  (%zu samples)\n",
                  s.name.c_str(), l, n, med, p99, us.size());
    }
    if (ns.size() >= 2) {
      const auto f = fit_power(ns, meds);
      fit_csv.row_text(
          {s.name, s.kind, teleop::format_number(f[0]), teleop::format_number(f[1]),
           teleop::format_number(f[2]),
           std::to_string(min_level) + "-" + std::to_string(std::min(top, s.max_level))});
      std::printf("%-32s cost ~ n^%.3f  (r^2 %.4f)\n", s.name.c_str(), f[0], f[2]);
    }
  }
  csv.flush();
  fit_csv.flush();
}

int bench_growth(const teleop::CommandArgs& a) {
  const int min_level = 2;
  const int top = a.quick ? 3 : 6;
  const int rounds = std::stoi(a.option("--rounds", a.quick ? "1" : "3"));
  const std::vector<Series> series = growth_series();
  const Samples samples = collect_samples(series, min_level, top, rounds, a.quick);
  write_growth(a.out_dir, series, samples, min_level, top);
  if (!a.no_chart) {
    teleop::run_chart_script(
        "growth.py", {(a.out_dir / "growth.csv").string(), (a.out_dir / "growth_fit.csv").string(),
                      (a.out_dir / "growth.png").string()});
  }
  return 0;
}

TELEOP_REGISTER_COMMAND(bench, "growth",
                        "step time against nodes (levels 2-6) and collision query against "
                        "triangles, with log-log fitted exponents",
                        bench_growth, teleop::integer_option("--rounds", 1, 100, "rounds"));

}  // namespace
