// teleop_bench deformable --out DIR [--quick] [--no-chart]
// Speed against accuracy of every model x integrator x mesh level on one disturbance:
// zero gravity, a smooth bump (5 mm radial, cos^2 profile, 30 degrees half-width) centred on
// icosahedron vertex 5 (present at every level at the same place), released at rest.
// Observable: the radial displacement r(t) - r0 of vertex 5, sampled every 1 ms over 0-0.1 s.
// Reference per model: the finest level (6) with the finest step (62.5 us), symplectic Euler.
// error = RMS over the samples of (r(t) - r_ref(t)) [m]; "inf" when the run blew up.
// Every run takes single steps of dt (max_substeps 1: the integrator itself, not the automatic
// step). The mass-spring symplectic rows come twice: kernel scalar (default) and simd.
// Writes DIR/deformable.csv (model,integrator,level,dt_s,step_us_median,step_us_p99,error,kernel)
// and DIR/deformable.png (tests/charts/deformable_bench.py).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "common/util/csv.hpp"
#include "common/util/registry.hpp"
#include "common/util/stats.hpp"
#include "server/deformable/deformable.hpp"

namespace {

using namespace teleop::sim::deformable;

constexpr int kProbe = 5;  // icosahedron vertex (0, 1, phi) / |.|: same place at every level

struct RunResult {
  std::vector<double> samples;  // r(t) - r0 every sample_dt [m]
  std::vector<double> step_us;  // wall time of each step [us]
  bool blew_up = false;
};

DeformableParams bench_params(ModelKind model, IntegratorKind integ, int level,
                              KernelKind kernel = KernelKind::kScalar) {
  DeformableParams p;
  p.model = model;
  p.integrator = integ;
  p.kernel = kernel;
  p.level = level;
  p.centre_m.setZero();
  p.gravity_mps2.setZero();
  if (model != ModelKind::kMassSpring) p.radial_stiffness_n_per_m3 = 0.0;
  p.sleep_time_s = 1e9;
  p.max_substeps = 1;  // the integrator at this dt, as measured: no automatic sub-steps
  return p;
}

RunResult run(ModelKind model, IntegratorKind integ, int level, double dt, double t_end,
              double sample_dt, KernelKind kernel = KernelKind::kScalar) {
  const DeformableParams p = bench_params(model, integ, level, kernel);
  const DeformableModel m = make_model(make_mesh_for(p), p);
  DeformableState s = make_state(m);
  // the bump
  const Eigen::Vector3d axis = (m.mesh.vertices.col(kProbe) - m.rest_centre_m).normalized();
  const double half_width = 30.0 * M_PI / 180.0, amp = 0.005;
  for (int i = 0; i < m.node_count; ++i) {
    const Eigen::Vector3d u = (m.mesh.vertices.col(i) - m.rest_centre_m).normalized();
    const double theta = std::acos(std::clamp(u.dot(axis), -1.0, 1.0));
    if (theta < half_width) {
      const double c = std::cos(0.5 * M_PI * theta / half_width);
      s.x.col(i) += amp * c * c * u;
    }
  }
  const double r0 = (m.mesh.vertices.col(kProbe) - m.rest_centre_m).norm();
  RunResult out;
  const int steps = static_cast<int>(std::lround(t_end / dt));
  const int every = static_cast<int>(std::lround(sample_dt / dt));
  out.step_us.reserve(static_cast<std::size_t>(steps));
  for (int k = 0; k <= steps; ++k) {
    if (k % every == 0) {
      out.samples.push_back((s.x.col(kProbe) - centroid(m, s)).norm() - r0);
    }
    if (k == steps) break;
    const auto t0 = std::chrono::steady_clock::now();
    const StepStatus st = step(m, s, dt, nullptr);
    const auto t1 = std::chrono::steady_clock::now();
    out.step_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    if (st == StepStatus::kFaultReset) {
      out.blew_up = true;
      break;
    }
  }
  return out;
}

int bench_deformable(const teleop::CommandArgs& a) {
  const int max_level = a.quick ? 3 : 6;
  const int ref_level = a.quick ? 4 : 6;
  const double ref_dt = a.quick ? 1.25e-4 : 6.25e-5;
  const double t_end = a.quick ? 0.05 : 0.1;
  const double sample_dt = 1e-3;
  const std::vector<double> dts = {1e-3, 2.5e-4};
  const ModelKind models[] = {ModelKind::kMassSpring, ModelKind::kNavierLinear,
                              ModelKind::kNavierCorotational};
  const IntegratorKind integrators[] = {IntegratorKind::kExplicitEuler,
                                        IntegratorKind::kSymplecticEuler,
                                        IntegratorKind::kImplicitEuler};
  teleop::CsvWriter csv(
      (a.out_dir / "deformable.csv").string(),
      {"model", "integrator", "level", "dt_s", "step_us_median", "step_us_p99", "error", "kernel"});
  for (ModelKind model : models) {
    const RunResult ref =
        run(model, IntegratorKind::kSymplecticEuler, ref_level, ref_dt, t_end, sample_dt);
    std::printf(
        "reference %s: level %d dt %.3g s, peak |r - r0| %.3g mm%s\n", to_string(model), ref_level,
        ref_dt,
        1e3 * std::max(std::fabs(*std::max_element(ref.samples.begin(), ref.samples.end())),
                       std::fabs(*std::min_element(ref.samples.begin(), ref.samples.end()))),
        ref.blew_up ? " BLEW UP" : "");
    for (IntegratorKind integ : integrators) {
      for (int level = 1; level <= max_level; ++level) {
        for (double dt : dts) {
          // the mass-spring symplectic step also with the simd kernel (params.kernel)
          const bool simd_too =
              model == ModelKind::kMassSpring && integ == IntegratorKind::kSymplecticEuler;
          for (KernelKind kernel : {KernelKind::kScalar, KernelKind::kSimd}) {
            if (kernel == KernelKind::kSimd && !simd_too) continue;
            const RunResult r = run(model, integ, level, dt, t_end, sample_dt, kernel);
            double err = std::numeric_limits<double>::infinity();
            if (!r.blew_up && r.samples.size() == ref.samples.size()) {
              double sum = 0.0;
              for (std::size_t k = 0; k < r.samples.size(); ++k) {
                const double d = r.samples[k] - ref.samples[k];
                sum += d * d;
              }
              err = std::sqrt(sum / static_cast<double>(r.samples.size()));
            }
            const double med = teleop::percentile(r.step_us, 50.0);
            const double p99 = teleop::percentile(r.step_us, 99.0);
            csv.row_text(
                {to_string(model), to_string(integ), std::to_string(level),
                 teleop::format_number(dt), teleop::format_number(med), teleop::format_number(p99),
                 std::isfinite(err) ? teleop::format_number(err) : "inf", to_string(kernel)});
            csv.flush();
            std::printf(
                "%-20s %-17s %-6s level %d dt %-7.3g step median %9.1f us p99 %9.1f us  error %.3g "
                "m\n",
                to_string(model), to_string(integ), to_string(kernel), level, dt, med, p99, err);
          }
        }
      }
    }
  }
  if (!a.no_chart) {
    teleop::run_chart_script("deformable_bench.py", {(a.out_dir / "deformable.csv").string(),
                                                     (a.out_dir / "deformable.png").string()});
  }
  return 0;
}

TELEOP_REGISTER_COMMAND(bench, "deformable",
                        "deformable sphere: step time vs error, models x integrators x levels 1-6",
                        bench_deformable);

}  // namespace
