// teleop_experiment validate: every deformable model, at several mesh sizes and two materials,
// measured against physics (server/world/physics_validation.hpp): Hertz contact (the ball on the
// floor pressed by the tip, with and without its weight; the tip pressing a ball held at its
// centre), Lamb's S2, T2 and S0 frequencies of a free ball, and the independent CalculiX
// reference of tests/reference/calculix/ball_reference.csv (the same presses and the sag under
// the weight; a row per reference).
// Writes validation.csv (one row per model, integrator, mesh, material and quantity) and
// validation.png (tests/charts/validation.py).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "common/util/csv.hpp"
#include "common/util/registry.hpp"
#include "server/world/physics_validation.hpp"

namespace {

namespace df = teleop::sim::deformable;
namespace va = teleop::sim::validation;

struct Case {
  df::ModelKind model;
  df::IntegratorKind integrator;
  int level;
  va::Material material;
  bool nodal_pressure = true;        // the fem default; false: the element law
  double mass_scaling_step_s = 0.0;  // fem: mass scaling to this stable step (0: none)
};

std::string variant_name(const Case& c) {
  if (c.model != df::ModelKind::kFem) return "-";
  if (!c.nodal_pressure) return "element_strain";
  return c.mass_scaling_step_s > 0.0 ? "nodal_pressure_mass_scaled_1ms" : "nodal_pressure";
}

using RowFn = std::function<void(const Case&, const va::PressResult&, const std::string&, double,
                                 double, double, const std::string&, double)>;

/// One body: its Lamb, Hertz and CalculiX rows. Returns 1 if a run had faults, else 0.
int validate_case(const Case& c, const std::vector<double>& travels, bool quick, double lamb_s,
                  const std::map<std::string, double>& ccx, const RowFn& row) {
  int failures = 0;
  df::DeformableParams p = va::ball_params(c.model, c.integrator, c.level, c.material);
  p.nodal_pressure = c.nodal_pressure;
  p.mass_scaling_step_s = c.mass_scaling_step_s;
  const double weight = p.mass_kg * 9.81;
  std::fprintf(stderr, "validate: %s (%s) %s L%d %s\n", df::to_string(c.model),
               variant_name(c).c_str(), df::to_string(c.integrator), c.level,
               c.material.name.c_str());
  // Lamb
  va::PressResult shape;  // nodes and tets for the Lamb rows
  for (auto mode : {va::LambMode::kS2, va::LambMode::kT2, va::LambMode::kS0}) {
    const double ref = va::lamb_frequency_hz(mode, c.material, va::kBallRadiusM);
    double us = 0.0;
    const double f = va::free_vibration_hz(p, mode, lamb_s, ref, &us);
    const df::DeformableModel m = df::make_model(p);
    shape.nodes = m.state_node_count();
    shape.tets = c.model == df::ModelKind::kFem ? m.fem.tet_count : 0;
    row(c, shape, std::string("lamb_") + va::to_string(mode) + "_hz", 0.0, ref, f, "lamb", us);
  }
  const std::string mat = c.material.name;
  auto ccx_ref = [&](const std::string& case_name, const std::string& quantity, double travel_m) {
    const auto it = ccx.find(va::calculix_key(mat, case_name, quantity, travel_m));
    return it == ccx.end() ? std::numeric_limits<double>::quiet_NaN() : it->second;
  };
  // Hertz (and CalculiX): on the floor without and with the weight; held at the centre
  const va::PressResult free =
      va::press_ball(p, va::Support::kFloor, false, travels, 0.01, quick ? 0.1 : 0.2);
  failures += free.faults > 0;
  for (std::size_t k = 0; k < travels.size(); ++k) {
    const double ref =
        va::hertz_floor_force_n(c.material, va::kBallRadiusM, va::kTipRadiusM, travels[k], 0.0);
    row(c, free, "tip_force_floor_n", travels[k], ref, free.force_n[k], "hertz", free.step_us);
    const double cref = ccx_ref("tip_floor_nogravity", "tip_force", travels[k]);
    if (std::isfinite(cref)) {
      row(c, free, "tip_force_floor_n", travels[k], cref, free.force_n[k], "calculix",
          free.step_us);
    }
  }
  const va::PressResult heavy =
      va::press_ball(p, va::Support::kFloor, true, travels, 0.01, quick ? 0.6 : 1.5);
  failures += heavy.faults > 0;
  for (std::size_t k = 0; k < travels.size(); ++k) {
    const double ref =
        va::hertz_floor_force_n(c.material, va::kBallRadiusM, va::kTipRadiusM, travels[k], weight);
    row(c, heavy, "tip_force_floor_weight_n", travels[k], ref, heavy.force_n[k], "hertz",
        heavy.step_us);
    const double cref = ccx_ref("tip_floor_gravity", "tip_force", travels[k]);
    if (std::isfinite(cref)) {
      row(c, heavy, "tip_force_floor_weight_n", travels[k], cref, heavy.force_n[k], "calculix",
          heavy.step_us);
    }
  }
  row(c, heavy, "sag_top_m", 0.0, ccx_ref("sag_floor", "top_descent", 0.0), heavy.sag_top_m,
      "calculix", heavy.step_us);
  row(c, heavy, "sag_centre_m", 0.0, ccx_ref("sag_floor", "centre_descent", 0.0),
      heavy.sag_centre_m, "calculix", heavy.step_us);
  row(c, heavy, "floor_force_n", 0.0, weight, heavy.floor_force_n, "weight", heavy.step_us);
  if (c.model == df::ModelKind::kFem) {
    const va::PressResult held =
        va::press_ball(p, va::Support::kHeldCentre, false, travels, 0.01, 0.1);
    failures += held.faults > 0;
    for (std::size_t k = 0; k < travels.size(); ++k) {
      row(c, held, "tip_force_held_n", travels[k],
          va::hertz_tip_force_n(c.material, va::kBallRadiusM, va::kTipRadiusM, travels[k]),
          held.force_n[k], "hertz", held.step_us);
      // the CalculiX ball clamped over the same 25 mm central sphere
      const double cref = ccx_ref("tip_centre_held", "tip_force_clamp25mm", travels[k]);
      if (std::isfinite(cref)) {
        row(c, held, "tip_force_held_n", travels[k], cref, held.force_n[k], "calculix",
            held.step_us);
      }
    }
  }
  return failures;
}

int run_validate(const teleop::CommandArgs& args) {
  std::filesystem::create_directories(args.out_dir);
  const bool quick = args.quick;
  const std::vector<double> travels =
      quick ? std::vector<double>{2e-3, 5e-3} : std::vector<double>{1e-3, 2e-3, 5e-3, 10e-3, 20e-3};
  const double lamb_s = quick ? 0.6 : 1.0;
  const auto sym = df::IntegratorKind::kSymplecticEuler;
  const auto imp = df::IntegratorKind::kImplicitEuler;
  std::vector<Case> cases;
  if (quick) {
    cases = {{df::ModelKind::kFem, sym, 1, va::foam()},
             {df::ModelKind::kMassSpring, sym, 3, va::foam()}};
  } else {
    for (const va::Material& mat : {va::foam(), va::silicone()}) {
      for (int level : {1, 2, 3}) cases.push_back({df::ModelKind::kFem, sym, level, mat});
      cases.push_back({df::ModelKind::kFem, imp, 2, mat});
      for (int level : {1, 2, 3}) cases.push_back({df::ModelKind::kFem, sym, level, mat, false});
      // mass-scaled to one step per 1 ms world step (the default scene's ball)
      for (int level : {1, 2}) cases.push_back({df::ModelKind::kFem, sym, level, mat, true, 1e-3});
    }
    for (int level : {3, 4, 5})
      cases.push_back({df::ModelKind::kMassSpring, sym, level, va::foam()});
    for (auto model : {df::ModelKind::kNavierLinear, df::ModelKind::kNavierCorotational}) {
      for (int level : {3, 4}) cases.push_back({model, sym, level, va::foam()});
    }
  }
  const auto ccx = va::calculix_reference();
  teleop::CsvWriter csv(
      (args.out_dir / "validation.csv").string(),
      {"model", "variant", "integrator", "mesh", "nodes", "tets", "material", "quantity",
       "travel_mm", "reference", "value", "error_pct", "reference_source", "step_us"});
  const RowFn row = [&](const Case& c, const va::PressResult& r, const std::string& quantity,
                        double travel_m, double reference, double value, const std::string& source,
                        double step_us) {
    const double err = std::isfinite(reference) && reference != 0.0 && std::isfinite(value)
                           ? 100.0 * (value / reference - 1.0)
                           : std::numeric_limits<double>::quiet_NaN();
    const std::string variant = variant_name(c);
    csv.row_text({std::string(df::to_string(c.model)), variant,
                  std::string(df::to_string(c.integrator)), "L" + std::to_string(c.level),
                  std::to_string(r.nodes), std::to_string(r.tets), c.material.name, quantity,
                  va::travel_mm_text(travel_m), teleop::format_number(reference),
                  teleop::format_number(value), teleop::format_number(err), source,
                  teleop::format_number(step_us)});
  };
  int failures = 0;
  teleop::Progress progress("validate", static_cast<double>(cases.size()), "bodies");
  for (const Case& c : cases) {
    failures += validate_case(c, travels, quick, lamb_s, ccx, row);
    progress.add();
  }
  progress.finish();
  csv.flush();
  if (!args.no_chart) {
    teleop::run_chart_script("validation.py", {(args.out_dir / "validation.csv").string(),
                                               (args.out_dir / "validation.png").string()});
  }
  std::cout << "validate: " << cases.size() << " bodies, " << failures << " runs with faults -> "
            << (args.out_dir / "validation.csv").string() << "\n";
  return failures == 0 ? 0 : 1;
}

}  // namespace

TELEOP_REGISTER_COMMAND(experiments, "validate",
                        "every deformable model against physics: Hertz contact, Lamb's "
                        "vibrations, sag (CalculiX); validation.csv and validation.png",
                        run_validate);
