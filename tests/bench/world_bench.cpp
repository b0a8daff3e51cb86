// teleop_bench world --out DIR: wall time of one physics step of the assembled default scene
// (PUMA 560 in ODE, level-4 elastic sphere, tip-mesh contact, planes) in the phases of a
// session: the sphere settling under gravity, resting untouched (asleep), free motion of the
// robot above it, and the tip pressing into it. Writes DIR/world.csv (median, p90, p99, max)
// and DIR/world.png. --scene FILE benchmarks another scene; --dt S another step; --steps N
// another number of steps per phase.
//
// --pace 1 runs each step at its own deadline, one every dt, as the live server's loop does
// (RateLoop), instead of back to back: the difference is what sleeping between steps costs the
// step (idle states, caches and TLB refilled, clock ramp), apart from any network work.
// With it: --spin-us N busy-waits the last N us before each deadline, --dma-latency-us N holds
// /dev/cpu_dma_latency, --cpu N pins the thread, --realtime P runs it SCHED_FIFO (the remedies
// of common/util/realtime.hpp), --prewarm-us N reads the next step's data into the caches in
// the last N us before each deadline (sim::world_prewarm). The CSV's `pacing` column names the
// variant.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "common/config/config.hpp"
#include "common/util/clock.hpp"
#include "common/util/csv.hpp"
#include "common/util/prewarm.hpp"
#include "common/util/rate_loop.hpp"
#include "common/util/realtime.hpp"
#include "common/util/registry.hpp"
#include "common/util/stats.hpp"
#include "server/world/world.hpp"

namespace teleop::bench {
namespace {

/// The pacing remedies of the flags, checked: they need --pace 1 and must fit in a step.
RealtimeOptions pacing_options(const CommandArgs& args, double dt, bool paced) {
  RealtimeOptions rt;
  rt.spin_us = std::stoi(args.option("--spin-us", "0"));
  rt.dma_latency_us = std::stoi(args.option("--dma-latency-us", "-1"));
  rt.cpu = std::stoi(args.option("--cpu", "-1"));
  rt.priority = std::stoi(args.option("--realtime", "0"));
  rt.prewarm_us = std::stoi(args.option("--prewarm-us", "0"));
  if (!paced && (rt.spin_us > 0 || rt.dma_latency_us >= 0 || rt.prewarm_us > 0)) {
    throw config::ConfigError("--spin-us, --dma-latency-us and --prewarm-us need --pace 1");
  }
  if (std::max(rt.spin_us, rt.prewarm_us) * 1e-6 >= dt) {
    throw config::ConfigError("--spin-us and --prewarm-us must be shorter than the step (--dt)");
  }
  return rt;
}

/// The CSV's `pacing` column: paced or back to back, and the remedies in force.
std::string pacing_name(bool paced, const RealtimeOptions& rt, bool dma_held) {
  return std::string(paced ? "paced" : "back_to_back") +
         (rt.spin_us > 0 ? "_spin" + std::to_string(rt.spin_us) + "us" : "") +
         (rt.prewarm_us > 0 ? "_prewarm" + std::to_string(rt.prewarm_us) + "us" : "") +
         (dma_held ? "_dma" + std::to_string(rt.dma_latency_us) : "") +
         (rt.cpu >= 0 ? "_cpu" + std::to_string(rt.cpu) : "") +
         (rt.priority > 0 ? "_fifo" + std::to_string(rt.priority) : "");
}

/// Steps one world through the phases of a session, a row of world.csv and a line on stdout
/// per phase.
class PhaseBench {
 public:
  PhaseBench(const sim::WorldModel& model, sim::WorldData& w, CsvWriter& csv, Progress& progress,
             const std::string& pacing, double dt, bool paced, const RealtimeOptions& rt)
      : model_(model),
        w_(w),
        csv_(csv),
        progress_(progress),
        pacing_(pacing),
        dt_(dt),
        paced_(paced),
        rt_(rt) {}

  /// `steps` steps with the tip commanded to target(k) at step k.
  template <class Target>
  void run(const char* phase, int steps, Target target) {
    std::vector<double> us, parts[3];
    us.reserve(static_cast<std::size_t>(steps));
    int contact = 0, sleeping = 0;
    RateLoop loop(1.0 / dt_, 16, static_cast<std::int64_t>(rt_.spin_us) * 1000);
    for (int k = 0; k < steps; ++k) {
      if (paced_ && rt_.prewarm_us > 0) {
        loop.sleep_until_lead(static_cast<std::int64_t>(rt_.prewarm_us) * 1000);
        keep(sim::world_prewarm(model_, w_));
      }
      if (paced_) loop.wait();
      sim::WorldCommand c;
      c.position_m = target(k);
      const auto t0 = now_ns();
      sim::world_step(model_, w_, c, dt_, events_);
      us.push_back(static_cast<double>(now_ns() - t0) * 1e-3);
      parts[0].push_back(w_.cost.collision_us);
      parts[1].push_back(w_.cost.deformable_us);
      parts[2].push_back(w_.cost.slave_us);
      contact += w_.out.in_contact;
      if (!w_.bodies.empty()) sleeping += w_.bodies[0].state.sleeping;
      while (events_.pop(e_)) {
      }
      progress_.add();
    }
    report(phase, steps, us, parts, contact, sleeping);
  }

 private:
  void report(const char* phase, int steps, const std::vector<double>& us,
              const std::vector<double> (&parts)[3], int contact, int sleeping) {
    const Summary s = summarize(us), c = summarize(parts[0]), d = summarize(parts[1]),
                  sl = summarize(parts[2]);
    csv_.row_text({pacing_, phase, format_number(dt_), std::to_string(steps), format_number(s.p50),
                   format_number(s.p90), format_number(s.p99), format_number(s.max),
                   format_number(static_cast<double>(contact) / steps),
                   format_number(static_cast<double>(sleeping) / steps), format_number(c.p50),
                   format_number(d.p50), format_number(sl.p50)});
    std::printf(
        "%-10s %s dt %.4f s  step p50 %7.1f us  p90 %7.1f us  p99 %7.1f us  max %7.1f us  "
        "contact %3.0f%%  asleep %3.0f%%  p50 collision %.1f deformable %.1f slave %.1f us\n",
        phase, pacing_.c_str(), dt_, s.p50, s.p90, s.p99, s.max, 100.0 * contact / steps,
        100.0 * sleeping / steps, c.p50, d.p50, sl.p50);
  }

  const sim::WorldModel& model_;
  sim::WorldData& w_;
  CsvWriter& csv_;
  Progress& progress_;
  const std::string pacing_;
  const double dt_;
  const bool paced_;
  const RealtimeOptions rt_;
  sim::EventQueue events_;
  sim::SimEvent e_;
};

/// The highest node of the first deformable body (a point above the floor without one).
Eigen::Vector3d top_of_first_body(const sim::WorldData& w) {
  Eigen::Vector3d top(0.6, 0.0, 0.5);
  if (!w.bodies.empty()) {
    const auto& x = w.bodies[0].state.x;
    Eigen::Index i = 0;
    x.row(2).maxCoeff(&i);
    top = x.col(i);
  }
  return top;
}

int world(const CommandArgs& args) {
  const std::string scene_file =
      args.option("--scene", std::string(TELEOP_SOURCE_DIR) + "/deploy/scenes/default.yaml");
  const double dt = std::stod(args.option("--dt", "0.001"));
  const int n = std::stoi(args.option("--steps", args.quick ? "300" : "3000"));
  const bool paced = args.option("--pace", "0") == "1";
  const RealtimeOptions rt = pacing_options(args, dt, paced);
  const DmaLatencyHold dma(rt.dma_latency_us);
  if (!dma.problem().empty()) std::fprintf(stderr, "world: %s\n", dma.problem().c_str());
  if (rt.cpu >= 0 || rt.priority > 0) {
    const std::string problem = make_thread_realtime(rt);
    if (!problem.empty()) std::fprintf(stderr, "world: %s\n", problem.c_str());
  }
  const std::string pacing = pacing_name(paced, rt, dma.held());
  const sim::WorldModel model = sim::load_world_model(scene_file);
  sim::WorldData w = sim::make_world_data(model);
  CsvWriter csv((args.out_dir / "world.csv").string(),
                {"pacing", "phase", "dt_s", "steps", "step_us_median", "step_us_p90", "step_us_p99",
                 "step_us_max", "in_contact_fraction", "sleeping_fraction", "collision_us_median",
                 "deformable_us_median", "slave_us_median"});
  const Eigen::Vector3d start = w.out.tip_position_m;
  const Eigen::Vector3d top = top_of_first_body(w);
  Progress progress("world", 4.5 * n, "steps");
  PhaseBench bench(model, w, csv, progress, pacing, dt, paced, rt);
  const Eigen::Vector3d above = top + Eigen::Vector3d(0, 0, 0.1);
  bench.run("settling", n, [&](int) { return start; });
  bench.run("resting", n, [&](int) { return start; });
  bench.run("free", n, [&](int k) {
    const double a = 2 * M_PI * k * dt;
    return Eigen::Vector3d(above + 0.08 * Eigen::Vector3d(std::cos(a), std::sin(a), 0));
  });
  bench.run("approach", n / 2, [&](int k) {
    return Eigen::Vector3d(above + (top + Eigen::Vector3d(0, 0, 0.05) - above) *
                                       std::min(1.0, 2.0 * k / n));
  });
  const int press_steps = n / 3;  // the press reaches its depth in the first third
  bench.run("pressing", n, [&](int k) {
    const double depth = 0.02 * std::min(1.0, 1.0 * k / static_cast<double>(press_steps));
    return Eigen::Vector3d(top + Eigen::Vector3d(0, 0, 0.05 - depth));
  });
  progress.finish();
  csv.flush();
  if (!args.no_chart) {
    run_chart_script("world_bench.py", {(args.out_dir / "world.csv").string(),
                                        (args.out_dir / "world.png").string()});
  }
  return 0;
}

TELEOP_REGISTER_COMMAND(bench, "world", "physics step of the assembled default scene, by phase",
                        world, text_option("--scene", "scene YAML"),
                        number_option("--dt", 1e-5, 0.1, "time step [s]"),
                        integer_option("--steps", 30, 1000000, "steps per phase (3000)"),
                        integer_option("--pace", 0, 1, "1: one step per dt, as the live loop"),
                        integer_option("--spin-us", 0, 100000, "busy-wait before each deadline"),
                        integer_option("--prewarm-us", 0, 100000,
                                       "read the next step's data into the caches before each "
                                       "deadline"),
                        integer_option("--dma-latency-us", -1, 100000,
                                       "hold /dev/cpu_dma_latency (-1 = no)"),
                        integer_option("--cpu", -1, 1023, "pin to this CPU (-1 = no)"),
                        integer_option("--realtime", 0, 99, "SCHED_FIFO priority (0 = no)"));

}  // namespace
}  // namespace teleop::bench
