// teleop_bench peers-fem --out DIR [--quick] [--no-chart] [--rounds N]
// Our volumetric FEM ball against Bullet's deformable FEM (btDeformableMultiBodyDynamicsWorld
// with btDeformableLinearElasticityForce, Debian's libbullet-dev, single precision, implicit
// Euler by Newton-CG, and its explicit scheme) on the same tetrahedral meshes (the shipped balls of
// levels 1 and 2), the same material (the foam ball: E = 6000 Pa, nu = 0.3, 2 kg, lambda and mu
// given to both) and the same 1 ms world step, interleaved in one process run.
//
// Workload: zero gravity, no planes, no damping; the ball at rest gets the velocity field of
// Lamb's T2 or S2 mode (2 cm/s at most, physics_validation.hpp) and vibrates freely for 0.6 s (0.2
// s with --quick). Measured per engine, level and mode: wall time of each world step (median, p99
// over the rounds) and the frequency of the mode's coordinate against Lamb's [%] (NaN: no vibration
// in 0.3-2.5 times Lamb's frequency, or the body blew up). Writes DIR/peers_fem.csv; chart
// DIR/peers_fem.png (tests/charts/peers_fem.py).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "common/mesh/tet_mesh.hpp"
#include "common/util/csv.hpp"
#include "common/util/registry.hpp"
#include "common/util/stats.hpp"
#include "server/deformable/deformable.hpp"
#include "server/world/physics_validation.hpp"
#include "tests/bench/bullet_tet_ball.hpp"

namespace {

namespace df = teleop::sim::deformable;
namespace va = teleop::sim::validation;
using teleop::bench::mode_coordinate;
using teleop::bench::mode_field;

struct Run {
  std::vector<double> q;        ///< the mode's coordinate per step
  std::vector<double> step_us;  ///< wall time per world step
};

Run run_ours(int level, va::LambMode mode, double dt, int steps) {
  df::DeformableParams p =
      va::ball_params(df::ModelKind::kFem, df::IntegratorKind::kSymplecticEuler, level, va::foam());
  p.gravity_mps2.setZero();
  p.stiffness_damping_s = 0.0;
  p.mass_damping_per_s = 0.0;
  const df::DeformableModel m = df::make_model(p);
  df::DeformableState s = df::make_state(m);
  const Eigen::Matrix3Xd x0 = s.x;
  const Eigen::Matrix3Xd phi = mode_field(mode, x0);
  s.v = phi;
  Run r;
  for (int k = 0; k < steps; ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    df::step(m, s, dt, nullptr);
    const auto t1 = std::chrono::steady_clock::now();
    r.step_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    r.q.push_back(mode_coordinate(s.x, x0, phi, m.fem.mass_kg));
  }
  return r;
}

#ifdef TELEOP_HAVE_BULLET
Run run_bullet(int level, va::LambMode mode, double dt, int steps, bool implicit) {
  const teleop::mesh::TetMesh tm =
      teleop::mesh::ball_tet_mesh(level, va::kBallRadiusM, Eigen::Vector3d::Zero());
  teleop::bench::BulletModeRun b =
      teleop::bench::run_bullet_mode(tm, va::foam(), 2.0, mode, dt, steps, implicit);
  return Run{std::move(b.q), std::move(b.step_us)};
}
#endif

int run_peers_fem(const teleop::CommandArgs& args) {
#ifndef TELEOP_HAVE_BULLET
  std::cout << "peers-fem: skipped (built without Bullet: apt-get install libbullet-dev)\n";
  (void)args;
  return 0;
#else
  std::filesystem::create_directories(args.out_dir);
  const double dt = 1e-3;
  const int steps = args.quick ? 200 : 600;
  const int rounds = std::max(1, std::stoi(args.option("--rounds", args.quick ? "1" : "2")));
  const std::vector<int> levels = args.quick ? std::vector<int>{1} : std::vector<int>{1, 2};
  teleop::CsvWriter csv((args.out_dir / "peers_fem.csv").string(),
                        {"engine", "level", "nodes", "tets", "mode", "lamb_hz", "frequency_hz",
                         "error_pct", "step_us_median", "step_us_p99", "rounds"});
  const va::Material foam = va::foam();
  // levels x modes x engines x rounds
  teleop::Progress progress(
      "peers-fem", static_cast<double>(levels.size() * (args.quick ? 2 : 6) * rounds), "runs");
  for (int level : levels) {
    const teleop::mesh::TetMesh tm =
        teleop::mesh::ball_tet_mesh(level, 0.25, Eigen::Vector3d::Zero());
    const std::vector<va::LambMode> modes =
        args.quick ? std::vector<va::LambMode>{va::LambMode::kT2}
                   : std::vector<va::LambMode>{va::LambMode::kT2, va::LambMode::kS2};
    for (auto mode : modes) {
      const double lamb = va::lamb_frequency_hz(mode, foam, va::kBallRadiusM);
      const std::vector<std::string> engines =
          args.quick ? std::vector<std::string>{"ours", "bullet-implicit"}
                     : std::vector<std::string>{"ours", "bullet-implicit", "bullet-explicit"};
      for (const std::string& engine : engines) {
        std::vector<double> times;
        double f = 0.0;
        for (int round = 0; round < rounds; ++round) {
          const Run r = engine == "ours"
                            ? run_ours(level, mode, dt, steps)
                            : run_bullet(level, mode, dt, steps, engine == "bullet-implicit");
          times.insert(times.end(), r.step_us.begin(), r.step_us.end());
          if (round == 0) f = va::dominant_frequency_hz(r.q, dt, lamb);
          progress.add();
        }
        std::sort(times.begin(), times.end());
        const double median = times[times.size() / 2];
        const double p99 = times[std::min(times.size() - 1, times.size() * 99 / 100)];
        std::fprintf(
            stderr,
            "peers-fem: %s L%d %s: %.3f Hz (Lamb %.3f, %+.1f %%), step p50 %.0f us p99 %.0f us\n",
            engine.c_str(), level, va::to_string(mode), f, lamb, 100 * (f / lamb - 1), median, p99);
        csv.row_text({engine, std::to_string(level), std::to_string(tm.node_count()),
                      std::to_string(tm.tet_count()), va::to_string(mode),
                      teleop::format_number(lamb), teleop::format_number(f),
                      teleop::format_number(100 * (f / lamb - 1)), teleop::format_number(median),
                      teleop::format_number(p99), std::to_string(rounds)});
      }
    }
  }
  progress.finish();
  csv.flush();
  if (!args.no_chart) {
    teleop::run_chart_script("peers_fem.py", {(args.out_dir / "peers_fem.csv").string(),
                                              (args.out_dir / "peers_fem.png").string()});
  }
  std::cout << "peers-fem: " << (args.out_dir / "peers_fem.csv").string() << "\n";
  return 0;
#endif
}

}  // namespace

TELEOP_REGISTER_COMMAND(bench, "peers-fem",
                        "our volumetric FEM ball against Bullet's deformable FEM on the same "
                        "tetrahedral meshes: step cost and Lamb frequency error",
                        run_peers_fem, teleop::integer_option("--rounds", 1, 100, "rounds"));
