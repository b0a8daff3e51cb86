// teleop_bench deformable --out DIR [--quick] [--no-chart] [--rounds N] [--models A,B]
// Speed against physical accuracy of every deformable model, integrator and resolution, and of
// Bullet's tetrahedral soft body on the same tetrahedral meshes, in one run. Every body is the
// foam ball (E 6000 Pa, nu 0.3, 2 kg, radius 0.25 m) with the parameters every model derives from
// that material (sim::validation::ball_params: Navier and fem take E and nu, mass-spring its
// springs from mass_spring_from_material), the way a scene file builds it.
//
// Rows: mass_spring, navier_linear, navier_corotational on icosphere levels 2-5 (level 2 with
// --quick), fem on the shipped tetrahedral balls of levels 1-4 (1), each with explicit, symplectic
// and implicit Euler (mass_spring symplectic also with the simd kernel); bullet_fem (Bullet's
// btDeformableMultiBodyDynamicsWorld + btDeformableLinearElasticityForce on the same tet balls,
// tests/bench/bullet_tet_ball.hpp): its implicit step on levels 1-4 (1) and its explicit one on
// level 1 (not with --quick).
//
// Measured per row:
// fem symplectic on levels 1 and 2 also mass-scaled to one step per 1 ms world step
// (mass_scaling_step_s column; params.mass_scaling_step_s).
//  - cost: wall time of each 1 ms world step of the body as a scene runs it (its default damping,
//    the automatic sub-steps included, no gravity, vibrating freely from Lamb's S2 velocity
//    field), `rounds` rounds of 300 steps (1 x 100 with --quick): median and p99. Bullet: the
//    steps of its three Lamb runs (it has no damping to add);
//  - physical error [%] against physics, as `teleop_experiment validate` measures it
//    (sim::validation): the frequencies of the free vibrations started by the S2, T2 and S0
//    fields (no damping, no gravity, 1 s; 0.5 s with --quick) against Lamb's, and the force on the
//    tip pressing the ball resting on the floor under its weight 5 mm deep (settled 1.5 s; 0.3 s
//    with --quick) against the converged CalculiX ball (tests/reference/calculix). error_pct is the
//    largest |error| of the four (Bullet: of the three Lamb ones; it is not pressed), inf when one
//    could not be measured (the run blew up, or no vibration in 0.3-2.5 times Lamb's frequency; a
//    body none of whose three vibrations could be measured is not pressed).
// Writes DIR/deformable.csv (one row per body; the table `model: auto` reads,
// deploy/data/deformable.csv) and DIR/deformable.png (tests/charts/deformable_bench.py).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "common/util/csv.hpp"
#include "common/util/registry.hpp"
#include "common/util/stats.hpp"
#include "server/deformable/deformable.hpp"
#include "server/world/physics_validation.hpp"
#include "tests/bench/bullet_tet_ball.hpp"

namespace {

namespace df = teleop::sim::deformable;
namespace va = teleop::sim::validation;

constexpr double kDt = 1e-3;      // the world step [s]
constexpr double kPressM = 5e-3;  // the press's travel [m]
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const va::LambMode kModes[] = {va::LambMode::kS2, va::LambMode::kT2, va::LambMode::kS0};

struct Body {
  std::string model;  // df::to_string, or "bullet_fem"
  std::string integrator;
  df::ModelKind kind = df::ModelKind::kMassSpring;
  df::IntegratorKind integ = df::IntegratorKind::kSymplecticEuler;
  df::KernelKind kernel = df::KernelKind::kScalar;
  int level = 2;
  bool bullet = false, bullet_implicit = true;
  double mass_scaling_step_s = 0.0;  // fem: mass-scaled to this stable step
};

struct Settings {
  double lamb_s = 1.0, settle_s = 1.5;
  int rounds = 3, cost_steps = 300;
};

struct Measured {
  int nodes = 0, elements = 0, substeps = 1;
  std::vector<double> step_us;
  double lamb_pct[3] = {kNaN, kNaN, kNaN};  // S2, T2, S0
  double press_pct = kNaN;
};

double pct(double value, double reference) {
  return std::isfinite(value) && reference != 0.0 ? 100.0 * (value / reference - 1.0) : kNaN;
}

df::DeformableParams params_of(const Body& b) {
  df::DeformableParams p = va::ball_params(b.kind, b.integ, b.level, va::foam());
  p.kernel = b.kernel;
  p.mass_scaling_step_s = b.mass_scaling_step_s;
  return p;
}

// Ours: cost as a scene runs the body, Lamb's three frequencies, the press.
Measured measure_ours(const Body& b, const Settings& set, double press_ref_n) {
  Measured out;
  df::DeformableParams p = params_of(b);
  {
    df::DeformableParams free = p;
    free.gravity_mps2.setZero();
    const df::DeformableModel m = df::make_model(free);
    out.nodes = m.state_node_count();
    out.elements = b.kind == df::ModelKind::kFem
                       ? m.fem.tet_count
                       : static_cast<int>(m.edges.cols()) + (m.has_centre ? m.node_count : 0);
    out.substeps = m.substeps_for(kDt);
    out.step_us.reserve(static_cast<std::size_t>(set.rounds * set.cost_steps));
    for (int round = 0; round < set.rounds; ++round) {
      df::DeformableState s = df::make_state(m);
      s.v = teleop::bench::mode_field(va::LambMode::kS2, s.x);
      for (int k = 0; k < set.cost_steps; ++k) {
        const auto t0 = std::chrono::steady_clock::now();
        df::step(m, s, kDt, nullptr);
        const auto t1 = std::chrono::steady_clock::now();
        out.step_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
      }
    }
  }
  for (int k = 0; k < 3; ++k) {
    const double ref = va::lamb_frequency_hz(kModes[k], va::foam(), va::kBallRadiusM);
    std::uint64_t faults = 0;
    const double f = va::free_vibration_hz(p, kModes[k], set.lamb_s, ref, nullptr, &faults);
    out.lamb_pct[k] = faults == 0 ? pct(f, ref) : kNaN;
  }
  // no free vibration at all (explicit Euler blows up without damping at any step): its error
  // is inf whatever the press gives, and the press (damped, many sub-steps) is not run
  if (std::isnan(out.lamb_pct[0]) && std::isnan(out.lamb_pct[1]) && std::isnan(out.lamb_pct[2])) {
    return out;
  }
  const va::PressResult press =
      va::press_ball(p, va::Support::kFloor, true, {kPressM}, 0.01, set.settle_s);
  out.press_pct = press.faults == 0 ? pct(press.force_n[0], press_ref_n) : kNaN;
  return out;
}

#ifdef TELEOP_HAVE_BULLET
// Bullet's tetrahedral soft body on the same tet ball: Lamb's three frequencies, the cost of the
// steps of those runs.
Measured measure_bullet(const Body& b, const Settings& set) {
  Measured out;
  const teleop::mesh::TetMesh tm =
      teleop::mesh::ball_tet_mesh(b.level, va::kBallRadiusM, Eigen::Vector3d::Zero());
  out.nodes = tm.node_count();
  out.elements = tm.tet_count();
  const int steps = static_cast<int>(std::lround(set.lamb_s / kDt));
  out.step_us.reserve(static_cast<std::size_t>(3 * steps));
  for (int k = 0; k < 3; ++k) {
    const double ref = va::lamb_frequency_hz(kModes[k], va::foam(), va::kBallRadiusM);
    const teleop::bench::BulletModeRun r = teleop::bench::run_bullet_mode(
        tm, va::foam(), 2.0, kModes[k], kDt, steps, b.bullet_implicit);
    out.step_us.insert(out.step_us.end(), r.step_us.begin(), r.step_us.end());
    out.lamb_pct[k] = r.finite ? pct(va::dominant_frequency_hz(r.q, kDt, ref), ref) : kNaN;
  }
  return out;
}
#endif

// The bodies of the run: every model, integrator and level (--models: only those named).
std::vector<Body> bodies(bool quick, const std::string& only) {
  auto wanted = [&](const std::string& model) {
    return only.empty() || ("," + only + ",").find("," + model + ",") != std::string::npos;
  };
  std::vector<Body> out;
  const df::IntegratorKind integrators[] = {df::IntegratorKind::kExplicitEuler,
                                            df::IntegratorKind::kSymplecticEuler,
                                            df::IntegratorKind::kImplicitEuler};
  for (df::ModelKind model : {df::ModelKind::kMassSpring, df::ModelKind::kNavierLinear,
                              df::ModelKind::kNavierCorotational, df::ModelKind::kFem}) {
    if (!wanted(df::to_string(model))) continue;
    const bool fem = model == df::ModelKind::kFem;
    const int lo = fem ? 1 : 2, hi = quick ? lo : (fem ? teleop::mesh::kMaxBallTetLevel : 5);
    for (df::IntegratorKind integ : integrators) {
      for (int level = lo; level <= hi; ++level) {
        Body b{df::to_string(model), df::to_string(integ), model, integ};
        b.level = level;
        out.push_back(b);
        if (model == df::ModelKind::kMassSpring && integ == df::IntegratorKind::kSymplecticEuler) {
          b.kernel = df::KernelKind::kSimd;
          out.push_back(b);
        }
        // fem symplectic also mass-scaled to one step per world step, where that takes little
        // mass (levels 1 and 2: 0.2 % and 1.1 %; level 3 would need more than 2 %)
        if (fem && integ == df::IntegratorKind::kSymplecticEuler && level <= 2) {
          b.mass_scaling_step_s = kDt;
          out.push_back(b);
        }
      }
    }
  }
#ifdef TELEOP_HAVE_BULLET
  for (int level = 1; level <= (quick ? 1 : teleop::mesh::kMaxBallTetLevel); ++level) {
    if (!wanted("bullet_fem")) break;
    Body b{"bullet_fem", "implicit"};
    b.bullet = true;
    b.level = level;
    out.push_back(b);
    if (level == 1 && !quick) {  // its explicit step: ~18 ms per step at level 1, blows up at 2
      b.integrator = "explicit";
      b.bullet_implicit = false;
      out.push_back(b);
    }
  }
#endif
  return out;
}

std::string number_or_nan(double v) { return std::isnan(v) ? "nan" : teleop::format_number(v); }

int bench_deformable(const teleop::CommandArgs& a) {
  std::filesystem::create_directories(a.out_dir);
  const std::string only = a.option("--models", "");
  {
    std::stringstream list(only);
    for (std::string name; std::getline(list, name, ',');) {
      const std::vector<std::string> known = {"mass_spring", "navier_linear", "navier_corotational",
                                              "fem", "bullet_fem"};
      if (std::find(known.begin(), known.end(), name) == known.end()) {
        std::fprintf(stderr,
                     "command line: --models '%s': '%s' is not one of {mass_spring, "
                     "navier_linear, navier_corotational, fem, bullet_fem} (comma-separated)\n",
                     only.c_str(), name.c_str());
        return 2;
      }
    }
  }
  Settings set;
  if (a.quick) set = Settings{0.5, 0.3, 1, 100};
  set.rounds = std::stoi(a.option("--rounds", std::to_string(set.rounds)));
  const auto ccx = va::calculix_reference();
  const auto it = ccx.find(va::calculix_key("foam", "tip_floor_gravity", "tip_force", kPressM));
  if (it == ccx.end()) {
    std::fprintf(stderr, "deformable: no CalculiX row for the 5 mm press (tests/reference)\n");
    return 1;
  }
  const double press_ref_n = it->second;
  teleop::CsvWriter csv(
      (a.out_dir / "deformable.csv").string(),
      {"model", "integrator", "kernel", "level", "nodes", "elements", "dt_s", "substeps",
       "step_us_median", "step_us_p99", "cost_steps", "lamb_s2_pct", "lamb_t2_pct", "lamb_s0_pct",
       "press_5mm_pct", "error_pct", "mass_scaling_step_s"});
  const auto start = std::chrono::steady_clock::now();
  const std::vector<Body> all = bodies(a.quick, only);
  teleop::Progress progress("deformable", static_cast<double>(all.size()), "bodies");
  for (const Body& b : all) {
    Measured m;
#ifdef TELEOP_HAVE_BULLET
    m = b.bullet ? measure_bullet(b, set) : measure_ours(b, set, press_ref_n);
#else
    m = measure_ours(b, set, press_ref_n);
#endif
    // the largest |error|; inf when one is missing (Bullet is not pressed: its Lamb ones only)
    std::vector<double> errors(m.lamb_pct, m.lamb_pct + 3);
    if (!b.bullet) errors.push_back(m.press_pct);
    double err = 0.0;
    for (double e : errors) {
      err = std::isnan(e) ? std::numeric_limits<double>::infinity() : std::max(err, std::fabs(e));
      if (std::isinf(err)) break;
    }
    const double med = teleop::percentile(m.step_us, 50.0);
    const double p99 = teleop::percentile(m.step_us, 99.0);
    csv.row_text({b.model, b.integrator, df::to_string(b.kernel), std::to_string(b.level),
                  std::to_string(m.nodes), std::to_string(m.elements), teleop::format_number(kDt),
                  std::to_string(m.substeps), teleop::format_number(med),
                  teleop::format_number(p99), std::to_string(m.step_us.size()),
                  number_or_nan(m.lamb_pct[0]), number_or_nan(m.lamb_pct[1]),
                  number_or_nan(m.lamb_pct[2]), number_or_nan(m.press_pct),
                  std::isfinite(err) ? teleop::format_number(err) : "inf",
                  teleop::format_number(b.mass_scaling_step_s)});
    csv.flush();
    const double t =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::printf(
        "[%6.0f s] %-19s %-16s %-6s L%d %5d nodes: %9.1f us (p99 %9.1f, %d sub-steps)  S2 %+6.1f "
        "T2 %+6.1f S0 %+6.1f press %+6.1f -> %.3g %%%s\n",
        t, b.model.c_str(), b.integrator.c_str(), df::to_string(b.kernel), b.level, m.nodes, med,
        p99, m.substeps, m.lamb_pct[0], m.lamb_pct[1], m.lamb_pct[2], m.press_pct, err,
        b.mass_scaling_step_s > 0.0 ? " (mass-scaled)" : "");
    std::fflush(stdout);
    progress.add();
  }
  progress.finish();
  if (!a.no_chart) {
    teleop::run_chart_script("deformable_bench.py", {(a.out_dir / "deformable.csv").string(),
                                                     (a.out_dir / "deformable.png").string()});
  }
  return 0;
}

TELEOP_REGISTER_COMMAND(bench, "deformable",
                        "deformable ball: step cost against the physical error (Lamb, CalculiX "
                        "press) of every model, integrator and resolution, and Bullet's tet FEM",
                        bench_deformable, teleop::integer_option("--rounds", 1, 100, "rounds"),
                        teleop::text_option("--models",
                                            "only these models, comma-separated "
                                            "(mass_spring, ..., fem, bullet_fem)"));

}  // namespace
