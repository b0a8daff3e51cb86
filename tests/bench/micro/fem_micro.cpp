// Google Benchmark: one 1 ms world step of the volumetric FEM ball while the tip presses it.
//   teleop_microbench --benchmark_filter=Fem --benchmark_repetitions=10
// The foam ball (E = 6000 Pa, nu = 0.3, 2 kg, radius 0.25 m, the default damping) rests on the
// floor under gravity, settled first, with the 0.05 m tip 10 mm into its top, fixed: every step
// does the contact and the elastic work of a press.
// Arguments: the shipped tet mesh level, and n: mass scaling to a 1 ms / n stable step (0: none).
// Counters: nodes, tets, substeps (per world step), faults (must stay 0), the mass the scaling
// added [g] and the tip's force [N].
// The _Implicit variant takes one implicit Euler step per world step (cg_iters per step).
// The _Cold variant writes 64 MiB between steps (not timed): each step starts with the body's
// data out of the caches, as a live loop that sleeps between steps may find it.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <vector>

#include "server/deformable/deformable.hpp"
#include "server/world/physics_validation.hpp"

namespace {

namespace df = teleop::sim::deformable;
namespace va = teleop::sim::validation;

void run_fem_press(benchmark::State& bs, df::IntegratorKind integ, bool cold = false) {
  const int level = static_cast<int>(bs.range(0));
  df::DeformableParams p = va::ball_params(df::ModelKind::kFem, integ, level, va::foam());
  p.sleep_time_s = 1e9;
  // second argument n > 0: mass scaling to a stable step of 1 ms / n
  if (bs.range(1) > 0) p.mass_scaling_step_s = 1e-3 / static_cast<double>(bs.range(1));
  const std::vector<teleop::sim::Plane> planes(1);  // the floor z = 0
  const df::DeformableModel m = df::make_model(p, planes);
  df::DeformableState s = df::make_state(m);
  const double dt = 1e-3, tip_r = 0.05;
  // settle on the floor (velocities relaxed), then the tip 10 mm into the top node
  for (int k = 0; k < 1500; ++k) {
    df::step(m, s, dt, nullptr);
    s.v *= 0.97;
  }
  int top = 0;
  for (int i = 0; i < m.node_count; ++i) top = s.x(2, i) > s.x(2, top) ? i : top;
  const Eigen::Vector3d tip(s.x(0, top), s.x(1, top), s.x(2, top) + tip_r - 0.010);
  s.tip_radius_m = tip_r;
  s.tip_from_m = tip;
  s.tip_to_m = tip;
  s.tip_velocity_mps.setZero();
  for (int k = 0; k < 300; ++k) {
    df::step(m, s, dt, nullptr);
    s.v *= 0.97;
  }
  std::vector<char> evict(cold ? std::size_t{64} << 20 : 0);
  for (auto _ : bs) {
    if (cold) {
      bs.PauseTiming();
      for (std::size_t i = 0; i < evict.size(); i += 64) evict[i] = static_cast<char>(i);
      benchmark::ClobberMemory();
      bs.ResumeTiming();
    }
    df::step(m, s, dt, nullptr);
    benchmark::DoNotOptimize(s.x.data());
  }
  bs.counters["nodes"] = m.fem.node_count;
  bs.counters["tets"] = m.fem.tet_count;
  bs.counters["substeps"] = s.last_substeps;
  bs.counters["faults"] = static_cast<double>(s.fault_count);
  bs.counters["added_g"] = 1e3 * m.fem.added_mass_kg;
  bs.counters["tip_force_n"] = s.tip_force_n.norm();
  if (integ == df::IntegratorKind::kImplicitEuler) bs.counters["cg_iters"] = s.cg_iterations;
}

void BM_Fem_Pressed_Symplectic(benchmark::State& bs) {
  run_fem_press(bs, df::IntegratorKind::kSymplecticEuler);
}
void BM_Fem_Pressed_Cold(benchmark::State& bs) {
  run_fem_press(bs, df::IntegratorKind::kSymplecticEuler, true);
}
void BM_Fem_Pressed_Implicit(benchmark::State& bs) {
  run_fem_press(bs, df::IntegratorKind::kImplicitEuler);
}

BENCHMARK(BM_Fem_Pressed_Symplectic)
    ->ArgsProduct({{1, 2, 3}, {0}})
    ->Args({1, 1})
    ->Args({2, 1})
    ->Args({2, 2})
    ->Args({3, 2})
    ->Args({3, 3})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Fem_Pressed_Cold)->Args({2, 1})->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Fem_Pressed_Implicit)->ArgsProduct({{1, 2}, {0}})->Unit(benchmark::kMicrosecond);

}  // namespace
