// Google Benchmark: one step of the deformable sphere per level, model and integrator.
//   teleop_microbench --benchmark_filter=Deformable
// The body is kept awake and disturbed (a node 5 mm out, released) so every step does work.
// The steps below level 5 need no sub-steps (counter `substeps` = 1): one step is timed. The
// _1ms variants time a 1 ms world step at level 5, which the automatic step splits in 3.
//   --benchmark_repetitions=10 adds median, min and max over the repetitions.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <vector>

#include "server/deformable/deformable.hpp"

namespace {

using namespace teleop::sim::deformable;

void run_step(benchmark::State& bs, ModelKind model, IntegratorKind integ,
              KernelKind kernel = KernelKind::kScalar, double world_dt = 0.0) {
  DeformableParams p;
  p.model = model;
  p.integrator = integ;
  p.kernel = kernel;
  p.level = static_cast<int>(bs.range(0));
  p.gravity_mps2.setZero();
  p.sleep_time_s = 1e9;
  if (model != ModelKind::kMassSpring) p.radial_stiffness_n_per_m3 = 0.0;
  // a stable step for every level: w_max grows with each level (~1 / edge length, and faster
  // with the stiffness-proportional damping), so above level 4 the step is divided by 4 per
  // level; the `faults` counter must stay 0 for the timing to mean anything
  // (world_dt > 0: that step, sub-stepped by the automatic step as a world step would be)
  const double dt = world_dt > 0.0 ? world_dt
                                   : (integ == IntegratorKind::kExplicitEuler ? 0.1e-3 : 1e-3) /
                                         static_cast<double>(1 << (2 * std::max(0, p.level - 4)));
  const DeformableModel m = make_model(make_mesh_for(p), p, {});
  DeformableState s = make_state(m);
  s.x.col(0) += 0.005 * (s.x.col(0) - m.rest_centre_m).normalized();
  for (auto _ : bs) {
    step(m, s, dt, nullptr);
    benchmark::DoNotOptimize(s.x.data());
  }
  bs.counters["nodes"] = m.node_count;
  bs.counters["substeps"] = s.last_substeps;
  bs.counters["faults"] = static_cast<double>(s.fault_count);
  if (integ == IntegratorKind::kImplicitEuler) bs.counters["cg_iters"] = s.cg_iterations;
}

void BM_Deformable_MassSpring_Symplectic(benchmark::State& bs) {
  run_step(bs, ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler);
}
void BM_Deformable_MassSpring_Symplectic_Simd(benchmark::State& bs) {
  run_step(bs, ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler, KernelKind::kSimd);
}
// A 1 ms world step, sub-stepped where the level needs it (level 5: 3 sub-steps)
void BM_Deformable_MassSpring_Symplectic_1ms(benchmark::State& bs) {
  run_step(bs, ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler, KernelKind::kScalar, 1e-3);
}
void BM_Deformable_MassSpring_Symplectic_Simd_1ms(benchmark::State& bs) {
  run_step(bs, ModelKind::kMassSpring, IntegratorKind::kSymplecticEuler, KernelKind::kSimd, 1e-3);
}
void BM_Deformable_MassSpring_Implicit(benchmark::State& bs) {
  run_step(bs, ModelKind::kMassSpring, IntegratorKind::kImplicitEuler);
}
void BM_Deformable_NavierLinear_Symplectic(benchmark::State& bs) {
  run_step(bs, ModelKind::kNavierLinear, IntegratorKind::kSymplecticEuler);
}
void BM_Deformable_NavierCorot_Symplectic(benchmark::State& bs) {
  run_step(bs, ModelKind::kNavierCorotational, IntegratorKind::kSymplecticEuler);
}
void BM_Deformable_NavierCorot_Implicit(benchmark::State& bs) {
  run_step(bs, ModelKind::kNavierCorotational, IntegratorKind::kImplicitEuler);
}

double min_of(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }
double max_of(const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); }

BENCHMARK(BM_Deformable_MassSpring_Symplectic)
    ->DenseRange(1, 6)
    ->Unit(benchmark::kMicrosecond)
    ->ComputeStatistics("min", min_of)
    ->ComputeStatistics("max", max_of);
BENCHMARK(BM_Deformable_MassSpring_Symplectic_Simd)
    ->DenseRange(1, 6)
    ->Unit(benchmark::kMicrosecond)
    ->ComputeStatistics("min", min_of)
    ->ComputeStatistics("max", max_of);
BENCHMARK(BM_Deformable_MassSpring_Symplectic_1ms)->Arg(5)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Deformable_MassSpring_Symplectic_Simd_1ms)->Arg(5)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Deformable_MassSpring_Implicit)->DenseRange(1, 5)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Deformable_NavierLinear_Symplectic)->DenseRange(1, 6)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Deformable_NavierCorot_Symplectic)->DenseRange(1, 5)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Deformable_NavierCorot_Implicit)->DenseRange(1, 4)->Unit(benchmark::kMicrosecond);

}  // namespace
