// teleop_bench delay --out DIR [--quick] [--no-chart]
//
// Delay-robustness sweep of the bilateral schemes, in-process (no DDS): the Fig. 13 press
// task (SimulatedDevice + operator model -> controller -> DelayChannel -> slave -> back) at
// 1 kHz, for each scheme, one-way delay 0-200 ms against the environment (elastic sphere,
// stiff wall) and the gain (position-position: K_pm = K_ps; force-position: K_f), plus a
// stiffness sweep (sphere k 500 - 2e4 N/m). Each run's verdict is compared with the analytic
// delay margin of the linearised loop (client/analysis/stability_analysis.hpp).
//
// The passivity-based schemes run the same grid: wave-variables (gain = K_ps; b = K_ps 25 ms,
// at most 20 N s/m), tdpa (on position-position, gain = K_pm = K_ps) and tdpa-fp (tdpa on
// force-position, gain = K_f). Their "theory" is passivity: stable at every delay
// (theory_stable = 1); for tdpa the analytic margin column holds the base law's margin.
//
// Every run steps the server's own world in-process (server::WorldSlave: the watchdog, the
// passivity port and world_step of ServerCycle) on the scenario's tool world. The wall cases
// run twice (rows "point" and "tool_scene", names kept from when these were two slaves) and
// must agree.
//
// Writes delay_map.csv, delay_boundary.csv (first delay margin vs gain), delay_theory.csv
// (exact stable/unstable grid of the linear model), delay_summary.json; charts delay_map.png,
// delay_map_tdpa.png, delay_map_passive.png (tests/charts/delay_map.py), transparency.png.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "client/analysis/press_scenario.hpp"
#include "common/util/csv.hpp"
#include "common/util/files.hpp"
#include "common/util/json.hpp"
#include "common/util/progress.hpp"
#include "common/util/registry.hpp"
#include "common/util/stats.hpp"
#include "common/util/version.hpp"
#include "tests/support/press_world.hpp"

namespace {

using namespace teleop::master;
using namespace teleop;

/// Every run's slave is the server's own cycle on the scenario's tool world (WorldSlave:
/// ServerCycle + world_step); the "tool_scene" rows (the wall cases run a second time, without
/// the extra figures run_press collects) stay in the CSV to show the runs are reproducible.
using teleop::server::WorldSlave;

/// A figure for the CSV; "nan" where it was not measured.
std::string num(double v) { return std::isfinite(v) ? teleop::format_number(v) : "nan"; }

struct RunRow {
  std::string sweep, scheme, environment, slave;
  double k = 0, gain = 0, delay_ms = 0;
  PressResult r;
};

PressResult run_with(const PressScenario& s, bool tool_scene) {
  if (!tool_scene) return teleop::test::run_press_world(s);
  const PressSetup setup = build_press_setup(s);
  SimulatedDevice device(setup.device);
  WorldSlave slave(teleop::test::press_world(setup), setup.loop.dt_s);
  LoopbackSession session(setup.loop, device, slave);
  session.run();
  PressResult r;
  fill_metrics(session.metrics(), r);
  r.safety_cut = session.safety().cut();
  fill_analytic(s, setup, r);
  return r;
}

/// A sweep scheme: its label in the CSV and how to set up the scenario.
struct SweepScheme {
  const char* label;   ///< scheme column
  const char* scheme;  ///< controller scheme
  const char* base;    ///< tdpa base law ("" otherwise)
  bool force_gain;     ///< gain axis is K_f (else a stiffness in N/m)
  bool one_gain;       ///< the scheme has no gain to sweep: its default only
};
constexpr SweepScheme kSchemes[] = {
    {"position-position", "position-position", "", false, false},
    {"force-position", "force-position", "", true, false},
    {"wave-variables", "wave-variables", "", false, false},
    {"tdpa", "tdpa", "position-position", false, false},
    {"tdpa-fp", "tdpa", "force-position", true, false},
    {"model-mediated", "model-mediated", "", true, true},
};

/// The axes of the sweep: one-way delays, the gains of each kind of scheme, the stiffnesses.
struct SweepGrid {
  std::vector<double> delays_ms, pp_gains, fp_gains, stiffness;
};

SweepGrid sweep_grid(bool quick) {
  SweepGrid g;
  for (int d = 0; d <= 200; d += quick ? 50 : 10) g.delays_ms.push_back(d);
  g.pp_gains = quick ? std::vector<double>{200, 1000, 3000}
                     : std::vector<double>{100, 200, 300, 400, 600, 800, 1000, 1500, 2000, 3000};
  g.fp_gains = quick ? std::vector<double>{0.1, 0.5, 2.0}
                     : std::vector<double>{0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0, 1.5, 2.0, 3.0};
  g.stiffness =
      quick ? std::vector<double>{} : std::vector<double>{500, 1000, 2000, 5000, 10000, 20000};
  return g;
}

/// The number of runs the sweep makes.
std::size_t planned_runs(const SweepGrid& g) {
  std::size_t planned = 0;
  for (const SweepScheme& scheme : kSchemes) {
    const std::size_t n_gains =
        scheme.one_gain ? 1 : (scheme.force_gain ? g.fp_gains.size() : g.pp_gains.size());
    planned += (3 * n_gains + g.stiffness.size()) * g.delays_ms.size();
  }
  return planned;
}

/// One run of the press task: `scheme` against `env` of stiffness `k` at `gain` and one-way
/// delay `d_ms`.
RunRow run_one(const std::string& sweep, const SweepScheme& scheme, Environment env, double k,
               double gain, double d_ms, bool tool_scene) {
  PressScenario s;
  s.scheme = scheme.scheme;
  if (*scheme.base) s.tdpa_base = scheme.base;
  s.environment = env;
  s.env_stiffness_n_per_m = k;
  s.env_damping_ns_per_m = env == Environment::kWall ? 50.0 : 5.0;
  s.gain = gain;
  s.one_way_delay_s = d_ms * 1e-3;
  RunRow row;
  row.sweep = sweep;
  row.scheme = scheme.label;
  row.environment = env == Environment::kWall ? "wall" : "sphere";
  row.slave = tool_scene ? "tool_scene" : "point";
  row.k = k;
  row.gain = gain;
  row.delay_ms = d_ms;
  row.r = run_with(s, tool_scene);
  return row;
}

/// Every run of the sweep: per scheme, each gain against the sphere and the wall (twice), then
/// each stiffness of the sphere at the default gain, at every delay.
std::vector<RunRow> run_sweep(const SweepGrid& g, teleop::Progress& progress) {
  std::vector<RunRow> rows;
  auto add = [&](const std::string& sweep, const SweepScheme& scheme, Environment env, double k,
                 double gain, double d_ms, bool tool_scene) {
    rows.push_back(run_one(sweep, scheme, env, k, gain, d_ms, tool_scene));
    progress.add();
  };
  for (const SweepScheme& scheme : kSchemes) {
    const double default_gain = scheme.force_gain ? 1.0 : 400.0;
    const std::vector<double> only_default = {default_gain};
    const auto& gains = scheme.one_gain     ? only_default
                        : scheme.force_gain ? g.fp_gains
                                            : g.pp_gains;
    for (double gain : gains) {
      for (double d : g.delays_ms) {
        add("gain", scheme, Environment::kSphere, 2000.0, gain, d, false);
        add("gain", scheme, Environment::kWall, 2.0e4, gain, d, false);
        add("gain", scheme, Environment::kWall, 2.0e4, gain, d, true);
      }
    }
    for (double k : g.stiffness) {
      for (double d : g.delays_ms)
        add("stiffness", scheme, Environment::kSphere, k, default_gain, d, false);
    }
  }
  return rows;
}

/// Per scheme: point-slave runs, stable ones, agreement with its theory, verdict reasons.
struct SchemeStats {
  int runs = 0, stable = 0, agree = 0, base_unstable = 0, base_unstable_stable = 0;
  int saturation = 0;  // unstable / oscillating because the force sat at the limit
  int other = 0;       // unstable / oscillating for another reason
};

/// What the sweep's runs add up to.
struct Tally {
  int agree = 0, judged = 0;  ///< point runs of non-passive schemes where theory and run agree
  int tool_agree = 0, tool_pairs = 0;  ///< repeated wall runs with the first run's verdict
  std::vector<SchemeStats> stats = std::vector<SchemeStats>(std::size(kSchemes));
};

/// Passivity-based schemes are stable at every delay by design; the others by their margin.
bool theory_stable(const RunRow& row) { return row.r.passive_scheme || row.r.analytic_stable; }

/// Agreement with the theory and verdict reasons of the point runs, per scheme and overall.
void tally_point_runs(const std::vector<RunRow>& rows, Tally& t) {
  const auto scheme_index = [](const std::string& label) {
    for (std::size_t i = 0; i < std::size(kSchemes); ++i) {
      if (label == kSchemes[i].label) return i;
    }
    return std::size_t{0};
  };
  for (const RunRow& row : rows) {
    if (row.slave != "point") continue;
    const bool sim_stable = row.r.verdict == Verdict::kStable;
    if (!row.r.passive_scheme) {
      ++t.judged;
      t.agree += theory_stable(row) == sim_stable;
    }
    SchemeStats& st = t.stats[scheme_index(row.scheme)];
    ++st.runs;
    st.stable += sim_stable;
    st.agree += theory_stable(row) == sim_stable;
    if (!row.r.analytic_stable) {
      ++st.base_unstable;
      st.base_unstable_stable += sim_stable;
    }
    if (!sim_stable) {
      const bool sat = row.r.reason.find("saturation") != std::string::npos ||
                       row.r.reason.find("limit") != std::string::npos;
      (sat ? st.saturation : st.other) += 1;
    }
  }
}

/// The repeated wall runs ("tool_scene" rows) against the first ones ("point"): same verdict.
void tally_tool_scene_pairs(const std::vector<RunRow>& rows, Tally& t) {
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (rows[i].slave != "tool_scene") continue;
    for (std::size_t j = 0; j < rows.size(); ++j) {
      if (rows[j].slave == "point" && rows[j].sweep == rows[i].sweep &&
          rows[j].scheme == rows[i].scheme && rows[j].environment == rows[i].environment &&
          rows[j].gain == rows[i].gain && rows[j].delay_ms == rows[i].delay_ms &&
          rows[j].k == rows[i].k) {
        ++t.tool_pairs;
        t.tool_agree += rows[j].r.verdict == rows[i].r.verdict;
      }
    }
  }
}

/// delay_map.csv: one row per run.
void write_delay_map(const std::string& path, const std::vector<RunRow>& rows) {
  teleop::CsvWriter csv(path, {"sweep",
                               "scheme",
                               "environment",
                               "slave",
                               "stiffness_n_per_m",
                               "gain",
                               "delay_ms",
                               "verdict",
                               "verdict_code",
                               "reason",
                               "theory_stable",
                               "analytic_margin_ms",
                               "position_error_rms_mm",
                               "force_error_rms_n",
                               "max_device_force_n",
                               "energy_min_j",
                               "contact_time_s",
                               "safety_cut",
                               "free_force_mean_n",
                               "free_force_p99_n",
                               "felt_force_ratio",
                               "felt_stiffness_n_per_m",
                               "environment_stiffness_n_per_m",
                               "stiffness_ratio"});
  for (const RunRow& row : rows) {
    const double margin_ms = row.r.analytic_margin_s * 1e3;
    std::string reason = row.r.reason;
    std::replace(reason.begin(), reason.end(), ',', ';');
    std::replace(reason.begin(), reason.end(), ' ', '_');
    csv.row_text({row.sweep,
                  row.scheme,
                  row.environment,
                  row.slave,
                  teleop::format_number(row.k),
                  teleop::format_number(row.gain),
                  teleop::format_number(row.delay_ms),
                  verdict_name(row.r.verdict),
                  std::to_string(static_cast<int>(row.r.verdict)),
                  reason.empty() ? "-" : reason,
                  theory_stable(row) ? "1" : "0",
                  std::isfinite(margin_ms) ? teleop::format_number(margin_ms) : "inf",
                  teleop::format_number(row.r.position_error_rms_m * 1e3),
                  teleop::format_number(row.r.force_error_rms_n),
                  teleop::format_number(row.r.max_device_force_n),
                  teleop::format_number(row.r.energy_min_j),
                  teleop::format_number(row.r.contact_time_s),
                  row.r.safety_cut ? "1" : "0",
                  num(row.r.free_force_mean_n),
                  num(row.r.free_force_p99_n),
                  num(row.r.felt_force_ratio),
                  num(row.r.felt_stiffness_n_per_m),
                  num(row.r.environment_stiffness_n_per_m),
                  num(row.r.stiffness_ratio)});
  }
  csv.flush();
}

/// A delay_boundary.csv row: the analytic delay margin of scenario `s`.
void boundary_row(teleop::CsvWriter& bnd, const char* sweep, const std::string& scheme,
                  const char* environment, const PressScenario& s) {
  const DelayMargin m = task_delay_margin(press_loop_model(s, build_press_setup(s)));
  bnd.row_text({sweep, scheme, environment, teleop::format_number(s.env_stiffness_n_per_m),
                teleop::format_number(s.gain),
                std::isfinite(m.one_way_s) ? teleop::format_number(m.one_way_s * 1e3) : "inf",
                teleop::format_number(m.crossover_radps),
                teleop::format_number(m.phase_margin_rad * 180.0 / M_PI)});
}

/// delay_boundary.csv: the analytic boundary on a fine grid of gains and stiffnesses.
void write_delay_boundary(const std::string& path) {
  teleop::CsvWriter bnd(path, {"sweep", "scheme", "environment", "stiffness_n_per_m", "gain",
                               "margin_ms", "crossover_radps", "phase_margin_deg"});
  for (const std::string scheme : {"position-position", "force-position"}) {
    const bool pp = scheme == "position-position";
    for (int e = 0; e < 2; ++e) {
      for (int i = 0; i <= 120; ++i) {
        const double g =
            pp ? 50.0 * std::pow(3200.0 / 50.0, i / 120.0) : 0.03 * std::pow(4.0 / 0.03, i / 120.0);
        PressScenario s;
        s.scheme = scheme;
        s.environment = e ? Environment::kWall : Environment::kSphere;
        s.env_stiffness_n_per_m = e ? 2.0e4 : 2000.0;
        s.env_damping_ns_per_m = e ? 50.0 : 5.0;
        s.gain = g;
        boundary_row(bnd, "gain", scheme, e ? "wall" : "sphere", s);
      }
    }
    for (int i = 0; i <= 120; ++i) {
      const double k = 300.0 * std::pow(3.0e4 / 300.0, i / 120.0);
      PressScenario s;
      s.scheme = scheme;
      s.environment = Environment::kSphere;
      s.env_stiffness_n_per_m = k;
      s.gain = pp ? 400.0 : 1.0;
      boundary_row(bnd, "stiffness", scheme, "sphere", s);
    }
  }
  bnd.flush();
}

/// delay_theory.csv: the exact stable/unstable regions of the linear model on a grid
/// (stability switches): gain against the sphere, gain against the wall, sphere stiffness.
void write_delay_theory(const std::string& path, bool quick) {
  teleop::CsvWriter grid(path, {"sweep", "scheme", "environment", "y", "delay_ms", "stable"});
  const int ny = quick ? 12 : 40, nd = quick ? 21 : 51;
  for (const std::string scheme : {"position-position", "force-position"}) {
    const bool pp = scheme == "position-position";
    for (int panel = 0; panel < 3; ++panel) {
      for (int i = 0; i < ny; ++i) {
        const double u = static_cast<double>(i) / (ny - 1);
        PressScenario s;
        s.scheme = scheme;
        s.environment = panel == 1 ? Environment::kWall : Environment::kSphere;
        s.env_stiffness_n_per_m = panel == 1 ? 2.0e4 : 2000.0;
        s.env_damping_ns_per_m = panel == 1 ? 50.0 : 5.0;
        double y = 0.0;
        if (panel < 2) {
          y = pp ? 70.0 * std::pow(4300.0 / 70.0, u) : 0.04 * std::pow(4.2 / 0.04, u);
          s.gain = y;
        } else {
          y = 400.0 * std::pow(2.5e4 / 400.0, u);
          s.env_stiffness_n_per_m = y;
          s.gain = pp ? 400.0 : 1.0;
        }
        const LoopModel model = press_loop_model(s, build_press_setup(s));
        LoopModel free = model;
        free.env_stiffness_n_per_m = free.env_damping_ns_per_m = 0.0;
        const DelayCrossings cc = delay_crossings(model), cf = delay_crossings(free);
        for (int k = 0; k < nd; ++k) {
          const double d_ms = 205.0 * k / (nd - 1);
          const bool st = stable_at(cc, d_ms * 1e-3) && stable_at(cf, d_ms * 1e-3);
          grid.row_text({panel == 2 ? "stiffness" : "gain", scheme, panel == 1 ? "wall" : "sphere",
                         teleop::format_number(y), teleop::format_number(d_ms), st ? "1" : "0"});
        }
      }
    }
  }
  grid.flush();
}

/// Cost of one haptic cycle of the whole in-process loop with `scheme` (timed here, not in
/// tests) [us].
teleop::Summary loop_cost(const char* scheme) {
  PressScenario ts;
  ts.scheme = scheme;
  ts.one_way_delay_s = 0.05;
  ts.jitter_s = 0.002;
  const PressSetup setup = build_press_setup(ts);
  SimulatedDevice dev(setup.device);
  WorldSlave slave(teleop::test::press_world(setup), setup.loop.dt_s);
  LoopbackSession session(setup.loop, dev, slave);
  session.start();
  std::vector<double> step_us;
  step_us.reserve(10000);
  while (true) {
    const auto a = std::chrono::steady_clock::now();
    if (!session.step()) break;
    step_us.push_back(
        std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - a).count());
  }
  return teleop::summarize(step_us);
}

/// The loop step costs of the three scheme families.
struct LoopCosts {
  teleop::Summary pp, wave, tdpa;
};

/// delay_summary.json: the sweep's figures, overall and per scheme.
void write_delay_summary(const std::string& path, std::size_t runs, double sweep_s, const Tally& t,
                         const LoopCosts& cost) {
  // timings to the microsecond's thousandth, fractions to four decimals
  const auto rounded = [](double v, double scale) { return std::round(v * scale) / scale; };
  teleop::OrderedJson summary;
  summary["version"] = teleop::version_string();
  summary["runs"] = runs;
  summary["sweep_wall_s"] = rounded(sweep_s, 1e3);
  summary["theory_agreement"] =
      rounded(t.judged ? static_cast<double>(t.agree) / t.judged : 0.0, 1e4);
  summary["theory_judged_runs"] = t.judged;
  summary["tool_scene_vs_point_agreement"] =
      rounded(t.tool_pairs ? static_cast<double>(t.tool_agree) / t.tool_pairs : 0.0, 1e4);
  summary["tool_scene_pairs"] = t.tool_pairs;
  summary["loop_step_us_p50"] = rounded(cost.pp.p50, 1e3);
  summary["loop_step_us_p99"] = rounded(cost.pp.p99, 1e3);
  summary["loop_step_us_max"] = rounded(cost.pp.max, 1e3);
  summary["loop_step_us_p50_wave"] = rounded(cost.wave.p50, 1e3);
  summary["loop_step_us_p99_wave"] = rounded(cost.wave.p99, 1e3);
  summary["loop_step_us_p50_tdpa"] = rounded(cost.tdpa.p50, 1e3);
  summary["loop_step_us_p99_tdpa"] = rounded(cost.tdpa.p99, 1e3);
  teleop::OrderedJson& schemes = summary["schemes"];
  for (std::size_t i = 0; i < std::size(kSchemes); ++i) {
    const SchemeStats& c = t.stats[i];
    schemes[kSchemes[i].label] = {{"runs", c.runs},
                                  {"stable", c.stable},
                                  {"theory_agreement", c.agree},
                                  {"base_theory_unstable", c.base_unstable},
                                  {"stable_where_base_theory_unstable", c.base_unstable_stable},
                                  {"not_stable_saturation", c.saturation},
                                  {"not_stable_other", c.other}};
  }
  teleop::write_text_file(path, teleop::json_compact(summary) + "\n");
}

/// The sweep's figures on stdout, overall and per scheme.
void print_delay_summary(std::size_t runs, double sweep_s, const Tally& t, const LoopCosts& cost) {
  std::printf(
      "delay sweep: %zu runs in %.2f s; simulation agrees with the analytic margin in "
      "%d/%d runs (position-position, force-position); wall runs repeated (rows tool_scene) agree "
      "in %d/%d "
      "runs; loop step p50 %.2f us, p99 %.2f us (wave %.2f / %.2f, tdpa %.2f / %.2f)\n",
      runs, sweep_s, t.agree, t.judged, t.tool_agree, t.tool_pairs, cost.pp.p50, cost.pp.p99,
      cost.wave.p50, cost.wave.p99, cost.tdpa.p50, cost.tdpa.p99);
  for (std::size_t i = 0; i < std::size(kSchemes); ++i) {
    const SchemeStats& c = t.stats[i];
    std::printf(
        "  %-18s %4d runs, %4d stable; %4d where the base law's theory is unstable, "
        "%4d of them stable; not stable: %d at the force limit, %d other\n",
        kSchemes[i].label, c.runs, c.stable, c.base_unstable, c.base_unstable_stable, c.saturation,
        c.other);
  }
}

int run_delay_bench(const teleop::CommandArgs& args) {
  const SweepGrid grid = sweep_grid(args.quick);
  teleop::Progress progress("delay", static_cast<double>(planned_runs(grid)));
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<RunRow> rows = run_sweep(grid, progress);
  const double sweep_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  progress.finish();

  Tally tally;
  tally_point_runs(rows, tally);
  write_delay_map((args.out_dir / "delay_map.csv").string(), rows);
  tally_tool_scene_pairs(rows, tally);
  write_delay_boundary((args.out_dir / "delay_boundary.csv").string());
  write_delay_theory((args.out_dir / "delay_theory.csv").string(), args.quick);
  const LoopCosts cost{loop_cost("position-position"), loop_cost("wave-variables"),
                       loop_cost("tdpa")};
  write_delay_summary((args.out_dir / "delay_summary.json").string(), rows.size(), sweep_s, tally,
                      cost);
  print_delay_summary(rows.size(), sweep_s, tally, cost);

  if (!args.no_chart) {
    teleop::run_chart_script(
        "delay_map.py",
        {(args.out_dir / "delay_map.csv").string(), (args.out_dir / "delay_boundary.csv").string(),
         (args.out_dir / "delay_theory.csv").string(), (args.out_dir / "delay_map.png").string()});
    teleop::run_chart_script("transparency.py", {(args.out_dir / "delay_map.csv").string(),
                                                 (args.out_dir / "transparency.png").string()});
  }
  return 0;
}

}  // namespace

TELEOP_REGISTER_COMMAND(bench, "delay",
                        "delay-robustness map of the bilateral schemes vs the analytic margin",
                        run_delay_bench);
