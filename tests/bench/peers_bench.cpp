// teleop_bench peers --out DIR [--quick] [--no-chart] [--rounds N]
// Our elastic sphere against Bullet's soft body (btSoftBody, Debian's libbullet-dev, single
// precision) on the same icosphere, interleaved in one process run.
//
// Workload (per engine, level and world step): zero gravity, no planes; icosahedron vertex 5
// pulled 5 mm radially outward (only that node) and released at rest; 1 s of simulated time in
// world steps of dt. Measured:
//   - wall time of each world step (ours: step(), which sub-steps by itself when dt exceeds the
//     stable step; Bullet: btSoftRigidDynamicsWorld::stepSimulation(dt, 0), one step of dt);
//   - overshoot: how far the released node goes inside its rest radius (distance to the body's
//     centroid) [mm]; residual: |its radial offset| at the end [mm];
//   - drift: how far the centroid of the surface nodes moved from where it started [mm] (the
//     body is free and starts at rest: it should not move);
//   - volume error: enclosed volume of the surface against the rest volume, largest |dV/V0| over
//     the run and at the end [%].
// Matched: the mesh (same vertices and triangles, make_icosphere), total mass 2 kg lumped by
// area (ours: a third of each triangle, 30 % in the centre node; Bullet: setTotalMass(2, true),
// by face area), the world step. Not matchable: Bullet's stiffness is a position-based
// correction fraction (kLST in [0, 1], here 1, its stiffest) applied piterations times per step,
// not N/m; its volume is kept by a gas pressure kPR / V on every node (no radial springs).
// Bullet solves its links one after another (Gauss-Seidel), so its result depends on their order:
// its constraints are shuffled by its own randomizeConstraints() (a fixed seed, as Bullet's demos
// do; --bullet-randomize 0 keeps the mesh's order). Measured: on the icosphere in our vertex
// order (reverse Cuthill-McKee, tri_mesh.hpp) unshuffled, Bullet's level-5 body blows up at 1 ms
// and at 0.25 ms and its level-4 centroid drifts by 1.4-8.4 mm; shuffled, it is stable at both
// levels with the accuracy it had on the earlier creation-order mesh.
// Rounds: every round runs every configuration once in rotating order (interleaved); the step
// times of all rounds are pooled (median, p99); the accuracy figures come from round 1 (all
// engines are deterministic).
// Writes DIR/peers.csv and DIR/peers_trace.csv; chart DIR/peers.png (tests/charts/peers.py).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "common/mesh/tri_mesh.hpp"
#include "common/util/csv.hpp"
#include "common/util/registry.hpp"
#include "common/util/stats.hpp"
#include "server/deformable/deformable.hpp"

#ifdef TELEOP_HAVE_BULLET
#include <BulletSoftBody/btSoftBodyHelpers.h>
#include <BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h>
#include <BulletSoftBody/btSoftRigidDynamicsWorld.h>
#include <btBulletDynamicsCommon.h>

#include <memory>
#endif

namespace {

using namespace teleop::sim::deformable;

constexpr int kProbe = 5;           // icosahedron vertex: the same place at every level
constexpr double kPull_m = 0.005;   // released node pulled out by this much [m]
constexpr double kRadius_m = 0.25;  // [m]
constexpr double kMass_kg = 2.0;

/// One run's measurements.
struct Trace {
  std::vector<double> step_us;
  std::vector<double> t_s, probe_mm, volume_pct;  // every sample
  double overshoot_mm = 0.0, residual_mm = 0.0, drift_mm = 0.0, max_volume_pct = 0.0,
         end_volume_pct = 0.0;
  bool failed = false;
};

double enclosed_volume(const Eigen::Matrix3Xi& tris, const Eigen::Matrix3Xd& x) {
  double v = 0.0;
  for (Eigen::Index t = 0; t < tris.cols(); ++t) {
    v += x.col(tris(0, t)).dot(x.col(tris(1, t)).cross(x.col(tris(2, t))));
  }
  return v / 6.0;
}

/// Engine-independent bookkeeping of one run: positions -> probe offset, centroid, volume.
class Recorder {
 public:
  Recorder(const teleop::mesh::TriMesh& mesh, const Eigen::Matrix3Xd& x0)
      : tris_(mesh.triangles), rest_r_((mesh.vertices.col(kProbe)).norm()) {
    v0_ = enclosed_volume(tris_, mesh.vertices);
    c0_ = x0.rowwise().mean();
  }
  void sample(Trace& tr, double t, const Eigen::Matrix3Xd& x) {
    const Eigen::Vector3d c = x.rowwise().mean();
    const double off_mm = 1e3 * ((x.col(kProbe) - c).norm() - rest_r_);
    const double vol_pct = 100.0 * (enclosed_volume(tris_, x) / v0_ - 1.0);
    tr.t_s.push_back(t);
    tr.probe_mm.push_back(off_mm);
    tr.volume_pct.push_back(vol_pct);
    tr.overshoot_mm = std::max(tr.overshoot_mm, -off_mm);
    tr.max_volume_pct = std::max(tr.max_volume_pct, std::fabs(vol_pct));
    tr.residual_mm = std::fabs(off_mm);
    tr.end_volume_pct = vol_pct;
    tr.drift_mm = 1e3 * (c - c0_).norm();
    if (!x.allFinite()) tr.failed = true;
  }

 private:
  Eigen::Matrix3Xi tris_;
  double rest_r_;
  double v0_;
  Eigen::Vector3d c0_;
};

/// Our sphere: the default material, zero gravity, no planes, the automatic step on.
Trace run_ours(int level, double dt, double t_end, double sample_dt, KernelKind kernel,
               int* substeps_out) {
  DeformableParams p;
  p.level = level;
  p.radius_m = kRadius_m;
  p.mass_kg = kMass_kg;
  p.centre_m.setZero();
  p.gravity_mps2.setZero();
  p.kernel = kernel;
  p.sleep_time_s = 1e9;
  const DeformableModel m = make_model(make_mesh_for(p), p);
  DeformableState s = make_state(m);
  const Eigen::Vector3d u = m.mesh.vertices.col(kProbe).normalized();
  s.x.col(kProbe) += kPull_m * u;
  Trace tr;
  Recorder rec(m.mesh, s.x);
  const int steps = static_cast<int>(std::lround(t_end / dt));
  const int every = std::max(1, static_cast<int>(std::lround(sample_dt / dt)));
  tr.step_us.reserve(static_cast<std::size_t>(steps));
  for (int k = 0; k <= steps; ++k) {
    if (k % every == 0) rec.sample(tr, k * dt, s.x);
    if (k == steps) break;
    const auto t0 = std::chrono::steady_clock::now();
    const StepStatus st = step(m, s, dt, nullptr);
    const auto t1 = std::chrono::steady_clock::now();
    tr.step_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    if (st == StepStatus::kFaultReset) tr.failed = true;
  }
  *substeps_out = m.substeps_for(dt);
  return tr;
}

#ifdef TELEOP_HAVE_BULLET
bool g_bullet_randomize = true;  // randomizeConstraints() before the run (--bullet-randomize 0|1)
double g_bullet_pressure = 2.0;  // kPR [J]: p = kPR / V on every node (--bullet-kpr)
constexpr double kOurDrag_per_s = 10.0;  // our mass_damping_per_s default: Bullet's kDP = it x dt

/// Bullet's soft body on the same mesh, mass and step.
Trace run_bullet(int level, double dt, double t_end, double sample_dt, int piterations) {
  const teleop::mesh::TriMesh mesh =
      teleop::mesh::make_icosphere(level, kRadius_m, Eigen::Vector3d::Zero());
  std::vector<btScalar> verts(static_cast<std::size_t>(mesh.vertices.size()));
  for (Eigen::Index i = 0; i < mesh.vertices.cols(); ++i) {
    for (int r = 0; r < 3; ++r) {
      verts[static_cast<std::size_t>(3 * i + r)] = static_cast<btScalar>(mesh.vertices(r, i));
    }
  }
  std::vector<int> tris(static_cast<std::size_t>(mesh.triangles.size()));
  for (Eigen::Index t = 0; t < mesh.triangles.cols(); ++t) {
    for (int r = 0; r < 3; ++r) tris[static_cast<std::size_t>(3 * t + r)] = mesh.triangles(r, t);
  }
  auto config = std::make_unique<btSoftBodyRigidBodyCollisionConfiguration>();
  auto dispatcher = std::make_unique<btCollisionDispatcher>(config.get());
  auto broadphase = std::make_unique<btDbvtBroadphase>();
  auto solver = std::make_unique<btSequentialImpulseConstraintSolver>();
  auto world = std::make_unique<btSoftRigidDynamicsWorld>(dispatcher.get(), broadphase.get(),
                                                          solver.get(), config.get());
  world->setGravity(btVector3(0, 0, 0));
  btSoftBodyWorldInfo& info = world->getWorldInfo();
  info.m_gravity.setValue(0, 0, 0);
  info.air_density = 0;
  info.water_density = 0;
  info.m_sparsesdf.Initialize();
  btSoftBody* sb = btSoftBodyHelpers::CreateFromTriMesh(
      info, verts.data(), tris.data(), static_cast<int>(mesh.triangles.cols()), false);
  sb->m_materials[0]->m_kLST = 1.0;  // its stiffest
  sb->m_cfg.piterations = piterations;
  sb->m_cfg.kPR = static_cast<btScalar>(g_bullet_pressure);
  sb->m_cfg.kDP = static_cast<btScalar>(kOurDrag_per_s * dt);  // v *= 1 - kDP each step
  sb->setTotalMass(static_cast<btScalar>(kMass_kg), true);
  if (g_bullet_randomize) sb->randomizeConstraints();
  world->addSoftBody(sb);
  // Bullet recomputes its runtime constants (and resets the links' rest lengths to the current
  // positions) on the first step after setTotalMass: do it now, at the rest shape
  sb->updateConstants();
  sb->m_bUpdateRtCst = false;
  const btVector3 u = sb->m_nodes[kProbe].m_x.normalized();
  sb->m_nodes[kProbe].m_x += u * static_cast<btScalar>(kPull_m);
  sb->m_nodes[kProbe].m_q = sb->m_nodes[kProbe].m_x;
  Eigen::Matrix3Xd x(3, sb->m_nodes.size());
  auto read = [&] {
    for (int i = 0; i < sb->m_nodes.size(); ++i) {
      const btVector3& p = sb->m_nodes[i].m_x;
      x.col(i) = Eigen::Vector3d(p.x(), p.y(), p.z());
    }
  };
  read();
  Trace tr;
  Recorder rec(mesh, x);
  const int steps = static_cast<int>(std::lround(t_end / dt));
  const int every = std::max(1, static_cast<int>(std::lround(sample_dt / dt)));
  tr.step_us.reserve(static_cast<std::size_t>(steps));
  for (int k = 0; k <= steps; ++k) {
    if (k % every == 0) {
      read();
      rec.sample(tr, k * dt, x);
    }
    if (k == steps) break;
    const auto t0 = std::chrono::steady_clock::now();
    world->stepSimulation(static_cast<btScalar>(dt), 0);
    const auto t1 = std::chrono::steady_clock::now();
    tr.step_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  world->removeSoftBody(sb);
  delete sb;
  return tr;
}
#endif

struct Config {
  std::string engine;  // "ours-scalar", "ours-simd", "bullet"
  int level;
  double dt;
};

/// Every (level, world step, engine) configuration; Bullet's only when it is built in.
std::vector<Config> peer_configs(const std::vector<int>& levels, const std::vector<double>& dts,
                                 bool have_bullet) {
  std::vector<Config> configs;
  for (int level : levels) {
    for (double dt : dts) {
      for (const char* e : {"ours-scalar", "ours-simd", "bullet"}) {
        if (std::string(e) == "bullet" && !have_bullet) continue;
        configs.push_back({e, level, dt});
      }
    }
  }
  return configs;
}

/// What the rounds measured, per configuration.
struct PeerResults {
  std::vector<std::vector<double>> times;  ///< step times of every round [us]
  std::vector<Trace> first;                ///< round 1's run
  std::vector<int> substeps;               ///< our sub-steps per world step (1 for Bullet)
};

/// Every configuration once per round, in an order rotated each round so no engine always
/// runs first or last.
PeerResults run_rounds(const std::vector<Config>& configs, int rounds, double t_end,
                       double sample_dt, [[maybe_unused]] int piterations) {
  PeerResults res;
  res.times.resize(configs.size());
  res.first.resize(configs.size());
  res.substeps.assign(configs.size(), 1);
  teleop::Progress progress("peers", static_cast<double>(rounds) * configs.size(), "runs");
  for (int r = 0; r < rounds; ++r) {
    for (std::size_t j = 0; j < configs.size(); ++j) {
      const std::size_t i = (j + static_cast<std::size_t>(r)) % configs.size();
      const Config& c = configs[i];
      Trace tr;
      if (c.engine == "bullet") {
#ifdef TELEOP_HAVE_BULLET
        tr = run_bullet(c.level, c.dt, t_end, sample_dt, piterations);
#endif
      } else {
        tr = run_ours(c.level, c.dt, t_end, sample_dt,
                      c.engine == "ours-simd" ? KernelKind::kSimd : KernelKind::kScalar,
                      &res.substeps[i]);
      }
      res.times[i].insert(res.times[i].end(), tr.step_us.begin(), tr.step_us.end());
      if (r == 0) res.first[i] = std::move(tr);
      progress.add();
    }
  }
  progress.finish();
  return res;
}

/// peers.csv (one row per configuration), peers_trace.csv (round 1's samples) and the table
/// on stdout.
void write_peers(const std::filesystem::path& out_dir, const std::vector<Config>& configs,
                 const PeerResults& res) {
  teleop::CsvWriter csv((out_dir / "peers.csv").string(),
                        {"engine", "level", "nodes", "dt_s", "substeps", "step_us_median",
                         "step_us_p99", "overshoot_mm", "residual_mm", "drift_mm",
                         "max_volume_error_pct", "end_volume_error_pct", "failed"});
  teleop::CsvWriter trace((out_dir / "peers_trace.csv").string(),
                          {"engine", "level", "dt_s", "t_s", "probe_mm", "volume_pct"});
  std::printf("%-12s %5s %6s %5s %10s %10s %9s %9s %9s %9s\n", "engine", "level", "dt_ms", "sub",
              "median_us", "p99_us", "overshoot", "residual", "drift_mm", "max_dV_%");
  for (std::size_t i = 0; i < configs.size(); ++i) {
    const Config& c = configs[i];
    const Trace& tr = res.first[i];
    const double med = teleop::percentile(res.times[i], 50.0);
    const double p99 = teleop::percentile(res.times[i], 99.0);
    const int nodes = 10 * (1 << (2 * c.level)) + 2;
    csv.row_text({c.engine, std::to_string(c.level), std::to_string(nodes),
                  teleop::format_number(c.dt), std::to_string(res.substeps[i]),
                  teleop::format_number(med), teleop::format_number(p99),
                  teleop::format_number(tr.overshoot_mm), teleop::format_number(tr.residual_mm),
                  teleop::format_number(tr.drift_mm), teleop::format_number(tr.max_volume_pct),
                  teleop::format_number(tr.end_volume_pct), tr.failed ? "1" : "0"});
    for (std::size_t k = 0; k < tr.t_s.size(); ++k) {
      trace.row_text({c.engine, std::to_string(c.level), teleop::format_number(c.dt),
                      teleop::format_number(tr.t_s[k]), teleop::format_number(tr.probe_mm[k]),
                      teleop::format_number(tr.volume_pct[k])});
    }
    std::printf("%-12s %5d %6.3g %5d %10.1f %10.1f %9.3f %9.3f %9.3f %9.3f%s\n", c.engine.c_str(),
                c.level, c.dt * 1e3, res.substeps[i], med, p99, tr.overshoot_mm, tr.residual_mm,
                tr.drift_mm, tr.max_volume_pct, tr.failed ? "  FAILED" : "");
  }
  // ratios: Bullet's median over ours at the same level and step
  for (std::size_t i = 0; i < configs.size(); ++i) {
    if (configs[i].engine != "bullet") continue;
    const double b = teleop::percentile(res.times[i], 50.0);
    for (std::size_t j = 0; j < configs.size(); ++j) {
      if (configs[j].engine == "bullet" || configs[j].level != configs[i].level ||
          configs[j].dt != configs[i].dt) {
        continue;
      }
      std::printf("ratio bullet / %s, level %d, dt %.3g ms: %.2fx\n", configs[j].engine.c_str(),
                  configs[i].level, configs[i].dt * 1e3,
                  b / teleop::percentile(res.times[j], 50.0));
    }
  }
  csv.flush();
  trace.flush();
}

int bench_peers(const teleop::CommandArgs& a) {
#ifdef TELEOP_HAVE_BULLET
  const bool have_bullet = true;
#else
  const bool have_bullet = false;
  std::printf(
      "teleop_bench peers: Bullet skipped: built without it (install libbullet-dev, e.g. "
      "deploy/setup.sh, and reconfigure); our sphere only\n");
#endif
  const std::vector<int> levels = a.quick ? std::vector<int>{1, 2, 3} : std::vector<int>{4, 5};
  const std::vector<double> dts = {1e-3, 2.5e-4};
  const int rounds = std::stoi(a.option("--rounds", a.quick ? "1" : "3"));
  const double t_end = a.quick ? 0.05 : 1.0;
  const double sample_dt = 1e-3;
  int piterations = 1;
#ifdef TELEOP_HAVE_BULLET
  piterations = std::stoi(a.option("--bullet-piterations", "1"));  // 1: its default
  g_bullet_pressure = std::stod(a.option("--bullet-kpr", "2"));
  const std::string randomize = a.option("--bullet-randomize", "1");
  if (randomize != "0" && randomize != "1") {
    std::fprintf(stderr, "teleop_bench peers: --bullet-randomize %s: allowed values 0, 1\n",
                 randomize.c_str());
    return 2;
  }
  g_bullet_randomize = randomize == "1";
#endif
  const std::vector<Config> configs = peer_configs(levels, dts, have_bullet);
  const PeerResults res = run_rounds(configs, rounds, t_end, sample_dt, piterations);
  write_peers(a.out_dir, configs, res);
  if (!a.no_chart) {
    teleop::run_chart_script(
        "peers.py", {(a.out_dir / "peers.csv").string(), (a.out_dir / "peers_trace.csv").string(),
                     (a.out_dir / "peers.png").string()});
  }
  return 0;
}

TELEOP_REGISTER_COMMAND(
    bench, "peers",
    "our sphere vs Bullet's soft body on the same icosphere: step time, "
    "overshoot and drift of a released node, volume error",
    bench_peers, teleop::integer_option("--rounds", 1, 100, "rounds"),
    teleop::integer_option("--bullet-piterations", 1, 1000, "Bullet iterations"),
    teleop::number_option("--bullet-kpr", 0, 1e6, "Bullet pressure coefficient"),
    teleop::integer_option("--bullet-randomize", 0, 1, "Bullet constraint order"));

}  // namespace
