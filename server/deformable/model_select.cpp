// Automatic model selection from the measured speed-accuracy table (model_select.hpp).
#include "server/deformable/model_select.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "common/util/data_dir.hpp"
#include "server/deformable/material.hpp"

namespace teleop::sim::deformable {

namespace {

using config::ConfigError;

constexpr double kToleranceMaxPct = 1000.0;
constexpr double kBudgetMaxUs = 1e6;

std::vector<std::string> split_csv_line(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) {
    while (!cell.empty() && (cell.back() == '\r' || cell.back() == ' ')) cell.pop_back();
    while (!cell.empty() && cell.front() == ' ') cell.erase(cell.begin());
    out.push_back(cell);
  }
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

double parse_number(const std::string& text, const std::string& where) {
  if (text == "inf" || text == "+inf") return std::numeric_limits<double>::infinity();
  try {
    std::size_t used = 0;
    const double v = std::stod(text, &used);
    if (used == text.size()) return v;
  } catch (const std::exception&) {
  }
  throw ConfigError(where + ": '" + text + "' is not a number");
}

/// v with `digits` significant digits (%g), or with `digits` decimals when fixed.
std::string fmt(double v, int digits, bool fixed = false) {
  char buf[64];
  if (fixed) {
    std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  } else {
    std::snprintf(buf, sizeof(buf), "%.*g", digits, v);
  }
  return buf;
}
std::string fmt4(double v) { return fmt(v, 4); }
std::string fmtg(double v) { return config::param_number_text(v); }  // as range_text writes
std::string fmt1(double v) { return fmt(v, 1, true); }

std::string ms_text(double s) { return fmt4(s * 1e3) + " ms"; }

/// The entry as a candidate for a world step of dt_s; false when it cannot run at that step.
bool as_candidate(const TableEntry& e, const ModelRequest& r, ModelChoice& out) {
  const double dt_s = r.physics_dt_s;
  if (!std::isfinite(e.error_pct) || !(e.dt_s > 0.0) || !(e.step_us_median >= 0.0)) return false;
  const double ratio = dt_s / e.dt_s;
  const double n = std::round(ratio);
  if (n < 1.0 || n > 10000.0 || std::fabs(ratio - n) > 1e-6 * n) return false;
  out.entry = e;
  out.substeps = static_cast<int>(n);
  out.cost_us_median = n * e.step_us_median;
  out.cost_us_p99 = n * e.step_us_p99;
  out.error_pct = e.error_pct;
  return true;
}

bool matches(const TableEntry& e, const ModelRequest& r) {
  return (!r.model || *r.model == e.model) && (!r.integrator || *r.integrator == e.integrator) &&
         (!r.level || *r.level == e.level) && (!r.kernel || *r.kernel == e.kernel);
}

/// Cheaper first; on equal cost the smaller error.
bool cheaper(const ModelChoice& a, const ModelChoice& b) {
  if (a.cost_us_median != b.cost_us_median) return a.cost_us_median < b.cost_us_median;
  return a.error_pct < b.error_pct;
}

/// The parameters the table's entries of `model` were measured with (tests/bench/
/// deformable_bench.cpp, validation::ball_params): a scene's body of that model made of the
/// default material (the foam), mass-spring springs derived from it.
DeformableParams table_params(ModelKind model) {
  YAML::Node y;
  y["model"] = to_string(model);
  y["youngs_modulus_pa"] = DeformableParams{}.youngs_modulus_pa;
  DeformableParams d = load_deformable_params(config::Node(y, "(table)", "body"));
  if (d.springs_from_material) {
    const MassSpringStiffness k = mass_spring_from_material(d.youngs_modulus_pa, d.poisson_ratio,
                                                            d.radius_m, d.centre_mass_fraction);
    d.edge_stiffness_n_per_m = k.edge_n_per_m;
    d.radial_stiffness_n_per_m3 = k.radial_n_per_m3;
  }
  return d;
}

/// The fields of a built body's parameters (springs resolved) that differ from the table's.
std::vector<std::string> differences_from_table(const DeformableParams& p) {
  const DeformableParams d = table_params(p.model);
  std::vector<std::string> out;
  auto cmp = [&](const char* name, double a, double b) {
    if (std::fabs(a - b) > 1e-9 * std::max(std::fabs(a), std::fabs(b))) out.emplace_back(name);
  };
  cmp("radius_m", p.radius_m, d.radius_m);
  if (p.density_kg_per_m3 > 0.0) {
    out.emplace_back("density_kg_per_m3");
  } else {
    cmp("mass_kg", p.mass_kg, d.mass_kg);
  }
  if (p.model != ModelKind::kMassSpring || p.springs_from_material) {
    cmp("youngs_modulus_pa", p.youngs_modulus_pa, d.youngs_modulus_pa);
    cmp("poisson_ratio", p.poisson_ratio, d.poisson_ratio);
  }
  if (p.model == ModelKind::kMassSpring) {
    if (!p.springs_from_material) {
      cmp("edge_stiffness_n_per_m", p.edge_stiffness_n_per_m, d.edge_stiffness_n_per_m);
      cmp("radial_stiffness_n_per_m3", p.radial_stiffness_n_per_m3, d.radial_stiffness_n_per_m3);
    }
    cmp("centre_mass_fraction", p.centre_mass_fraction, d.centre_mass_fraction);
    cmp("radial_damping_s", p.radial_damping_s, d.radial_damping_s);
  } else {
    cmp("radial_stiffness_n_per_m3", p.radial_stiffness_n_per_m3, d.radial_stiffness_n_per_m3);
  }
  cmp("stiffness_damping_s", p.stiffness_damping_s, d.stiffness_damping_s);
  cmp("mass_damping_per_s", p.mass_damping_per_s, d.mass_damping_per_s);
  if (p.model == ModelKind::kFem && p.nodal_pressure != d.nodal_pressure) {
    out.emplace_back("nodal_pressure");
  }
  if (p.integrator == IntegratorKind::kImplicitEuler) {
    cmp("cg_max_iterations", p.cg_max_iterations, d.cg_max_iterations);
    cmp("cg_tolerance", p.cg_tolerance, d.cg_tolerance);
  }
  return out;
}

/// Reads `key` as a number in (0, hi]; "value V is out of the allowed range (0, hi]".
double positive_number(const config::Node& n, const std::string& key, double hi) {
  if (!n.has(key)) n.fail(key, "is required with model, integrator, level or kernel: auto");
  return n.positive_number(key, hi);
}

bool is_auto(const config::Node& n, const std::string& key) { return n.is_text(key, "auto"); }

}  // namespace

std::string ModelChoice::name() const {
  std::string s = std::string(to_string(entry.model)) + " " + to_string(entry.integrator) + " " +
                  to_string(entry.kernel) + " level " + std::to_string(entry.level) + ", " +
                  std::to_string(substeps) + " x " + ms_text(entry.dt_s);
  if (entry.mass_scaling_step_s > 0.0)
    s += ", mass-scaled to " + ms_text(entry.mass_scaling_step_s);
  return s;
}

namespace {

/// Where each column of the table is (-1: absent).
struct TableColumns {
  int model = -1, integ = -1, level = -1, dt = -1, med = -1, p99 = -1, err = -1, kernel = -1,
      substeps = -1, s2 = -1, t2 = -1, s0 = -1, press = -1, mass_scaling = -1;
};

TableColumns table_columns(const std::vector<std::string>& header, const std::string& where) {
  TableColumns c;
  const std::pair<const char*, int*> names[] = {
      {"model", &c.model},         {"integrator", &c.integ},
      {"level", &c.level},         {"dt_s", &c.dt},
      {"step_us_median", &c.med},  {"step_us_p99", &c.p99},
      {"error_pct", &c.err},       {"kernel", &c.kernel},
      {"substeps", &c.substeps},   {"lamb_s2_pct", &c.s2},
      {"lamb_t2_pct", &c.t2},      {"lamb_s0_pct", &c.s0},
      {"press_5mm_pct", &c.press}, {"mass_scaling_step_s", &c.mass_scaling}};
  bool old_error = false;
  for (int i = 0; i < static_cast<int>(header.size()); ++i) {
    const std::string& h = header[static_cast<std::size_t>(i)];
    for (const auto& [name, col] : names) {
      if (h == name) *col = i;
    }
    old_error = old_error || h == "error";
  }
  if (c.err < 0 && old_error) {
    throw ConfigError(where +
                      ": the table has the former `error` column (metres against the same model "
                      "at level 6) and no `error_pct` (the physical error in %); re-measure it "
                      "with `teleop_bench deformable --out DIR --no-chart`");
  }
  if (c.model < 0 || c.integ < 0 || c.level < 0 || c.dt < 0 || c.med < 0 || c.p99 < 0 ||
      c.err < 0) {
    throw ConfigError(
        where +
        ": the header must name the columns model, integrator, level, dt_s, "
        "step_us_median, step_us_p99, error_pct (and optionally kernel, substeps, "
        "lamb_s2_pct, lamb_t2_pct, lamb_s0_pct, press_5mm_pct, mass_scaling_step_s), as "
        "`teleop_bench "
        "deformable` writes them");
  }
  return c;
}

/// One data row of the table. @throws ConfigError naming `where` and the bad cell.
TableEntry table_entry(const std::vector<std::string>& cells, const TableColumns& c,
                       const std::string& where) {
  auto cell = [&](int col) -> const std::string& { return cells[static_cast<std::size_t>(col)]; };
  auto number = [&](int col) { return parse_number(cell(col), where); };
  auto optional = [&](int col) {
    return col < 0 || cell(col).empty() || cell(col) == "nan"
               ? std::numeric_limits<double>::quiet_NaN()
               : number(col);
  };
  TableEntry e;
  try {
    e.model = parse_model_kind(cell(c.model));
    e.integrator = parse_integrator_kind(cell(c.integ));
  } catch (const ConfigError& err) {
    throw ConfigError(where + ": " + err.what());
  }
  if (c.kernel >= 0) {
    const std::string& k = cell(c.kernel);
    if (k == "simd") {
      e.kernel = KernelKind::kSimd;
    } else if (k != "scalar" && !k.empty()) {
      throw ConfigError(where + ": kernel '" + k + "' is not one of {scalar, simd}");
    }
  }
  const double level = number(c.level);
  if (level < 0 || level > 6 || level != std::floor(level)) {
    throw ConfigError(where + ": level " + cell(c.level) + " is not an integer in [0, 6]");
  }
  e.level = static_cast<int>(level);
  e.dt_s = number(c.dt);
  e.step_us_median = number(c.med);
  e.step_us_p99 = number(c.p99);
  e.error_pct = number(c.err);
  const double substeps = c.substeps < 0 ? 1.0 : number(c.substeps);
  if (!(e.dt_s > 0.0) || !std::isfinite(e.dt_s) || !(e.step_us_median >= 0.0) ||
      !std::isfinite(e.step_us_median) || std::isnan(e.error_pct) || e.error_pct < 0.0 ||
      !(substeps >= 1.0 && substeps <= 1e5) || substeps != std::floor(substeps)) {
    throw ConfigError(where +
                      ": dt_s must be > 0, step_us_median finite and >= 0, error_pct >= 0 or "
                      "inf, substeps an integer in [1, 100000]");
  }
  e.substeps = static_cast<int>(substeps);
  e.s2_pct = optional(c.s2);
  e.t2_pct = optional(c.t2);
  e.s0_pct = optional(c.s0);
  e.press_pct = optional(c.press);
  const double scaling = optional(c.mass_scaling);
  if (!std::isnan(scaling)) {
    if (!(scaling >= 0.0 && scaling <= 1.0)) {
      throw ConfigError(where + ": mass_scaling_step_s " + cell(c.mass_scaling) +
                        " is not in [0, 1] s");
    }
    if (scaling > 0.0 && e.model != ModelKind::kFem) {
      throw ConfigError(where + ": mass_scaling_step_s is for model fem only");
    }
    e.mass_scaling_step_s = scaling;
  }
  return e;
}

}  // namespace

ModelTable parse_model_table(const std::string& csv_text, const std::string& file) {
  ModelTable t;
  t.file = file;
  std::istringstream in(csv_text);
  std::string line;
  std::vector<std::string> header;
  TableColumns cols;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    const std::vector<std::string> cells = split_csv_line(line);
    const std::string where = file + ": line " + std::to_string(line_no);
    if (header.empty()) {
      header = cells;
      cols = table_columns(header, where);
      continue;
    }
    if (cells.size() < header.size()) {
      throw ConfigError(where + ": " + std::to_string(cells.size()) + " cells, the header has " +
                        std::to_string(header.size()));
    }
    // a peer measured beside ours for the chart (Bullet's tetrahedral soft body): not ours to run
    if (cells[static_cast<std::size_t>(cols.model)].rfind("bullet", 0) == 0) continue;
    t.entries.push_back(table_entry(cells, cols, where));
  }
  if (t.entries.empty()) throw ConfigError(file + ": the table has no entries");
  return t;
}

std::string default_model_table_file() { return data_path("data/deformable.csv"); }

ModelTable load_model_table(const std::string& file) {
  std::ifstream in(file);
  if (!in) {
    throw ConfigError(file +
                      ": cannot read the speed-accuracy table; measure it with `teleop_bench "
                      "deformable --out deploy/data --no-chart` (docs/deformable.md, \"Automatic "
                      "model\")");
  }
  std::ostringstream text;
  text << in.rdbuf();
  return parse_model_table(text.str(), file);
}

SelectResult select_model(const ModelTable& table, const ModelRequest& r) {
  SelectResult out;
  bool have_accurate = false, have_cheapest_accurate = false, have_choice = false;
  for (const TableEntry& e : table.entries) {
    ModelChoice c;
    if (!matches(e, r) || !as_candidate(e, r, c)) continue;
    ++out.matching;
    if (!have_accurate || c.error_pct < out.most_accurate.error_pct ||
        (c.error_pct == out.most_accurate.error_pct && cheaper(c, out.most_accurate))) {
      out.most_accurate = c;
      have_accurate = true;
    }
    if (!(c.error_pct <= r.tolerance_pct * (1.0 + 1e-9))) continue;  // inclusive, despite rounding
    ++out.within_tolerance;
    if (!have_cheapest_accurate || cheaper(c, out.cheapest_accurate)) {
      out.cheapest_accurate = c;
      have_cheapest_accurate = true;
    }
    if (!(c.cost_us_median <= r.budget_us * (1.0 + 1e-9))) continue;
    if (!have_choice || cheaper(c, out.choice)) {
      out.choice = c;
      have_choice = true;
    }
  }
  if (have_choice) {
    out.outcome = SelectOutcome::kChosen;
  } else if (out.matching == 0) {
    out.outcome = SelectOutcome::kNoEntry;
  } else if (out.within_tolerance == 0) {
    out.outcome = SelectOutcome::kTolerance;
  } else {
    out.outcome = SelectOutcome::kBudget;
  }
  return out;
}

std::string AutoBody::summary() const {
  if (!choice) return "";
  char buf[200];
  std::snprintf(buf, sizeof(buf), "auto: %s; predicted %.1f us/step (p99 %.0f), error %.3g %%%s",
                choice->name().c_str(), choice->cost_us_median * stability_factor,
                choice->cost_us_p99 * stability_factor, choice->error_pct,
                differs_from_table.empty() ? "" : " (other material)");
  std::string s = buf;
  if (s.size() > 127) s.resize(127);
  return s;
}

namespace {

/// "+1.2" (signed, 2 significant digits at most 1 decimal), "-" when not measured.
std::string signed_pct(double v) {
  if (std::isnan(v)) return "-";
  if (!std::isfinite(v)) return "none (blew up or no vibration)";
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%+.1f %%", v);
  return buf;
}

}  // namespace

std::string AutoBody::report() const {
  if (!choice) return "";
  const TableEntry& e = choice->entry;
  std::ostringstream o;
  o << "deformable auto: " << choice->name() << " (tolerance " << tolerance_pct << " %, budget "
    << budget_us << " us, table " << table_file << ")\n";
  o << "  predicted cost " << fmt1(choice->cost_us_median * stability_factor)
    << " us per world step (median; p99 " << fmt1(choice->cost_us_p99 * stability_factor)
    << " us), physical error " << fmt4(choice->error_pct) << " % (the largest of: Lamb S2 "
    << signed_pct(e.s2_pct) << ", T2 " << signed_pct(e.t2_pct) << ", S0 " << signed_pct(e.s0_pct)
    << ", 5 mm press on the floor against CalculiX " << signed_pct(e.press_pct)
    << "; teleop_bench deformable)";
  if (stability_factor > 1.0) {
    o << "\n  this body needs " << fmt4(stability_factor)
      << " times the table's stability sub-steps (cost included)";
  }
  if (!differs_from_table.empty()) {
    o << "\n  warning: the table was measured with the default material (foam); this body "
         "differs in";
    for (const std::string& d : differs_from_table) o << " " << d;
    o << ": the predicted error is an extrapolation";
  }
  return o.str();
}

bool has_auto_field(const config::Node& node) {
  return node.is_map() && (is_auto(node, "model") || is_auto(node, "integrator") ||
                           is_auto(node, "level") || is_auto(node, "kernel"));
}

namespace {

/// What an automatic body asks of the table: tolerance, budget and the fields it fixes.
ModelRequest model_request(const config::Node& node, double physics_dt_s) {
  ModelRequest req;
  req.physics_dt_s = physics_dt_s;
  if (node.has("tolerance_mm")) {
    node.fail("tolerance_mm",
              "was replaced by tolerance_pct: the largest physical error accepted, in % (the "
              "largest of Lamb's S2, T2, S0 frequency errors and the 5 mm press against the "
              "CalculiX ball), allowed range (0, " +
                  fmtg(kToleranceMaxPct) + "]; docs/deformable.md, \"Automatic model\"");
  }
  req.tolerance_pct = positive_number(node, "tolerance_pct", kToleranceMaxPct);
  req.budget_us = positive_number(node, "budget_us", kBudgetMaxUs);
  // the fixed fields, validated as load_deformable_params would
  if (!is_auto(node, "model") && node.has("model")) {
    req.model = parse_model_kind(node.choice(
        "model", {"auto", "mass_spring", "navier_linear", "navier_corotational", "fem"}));
  } else if (!node.has("model")) {
    req.model = ModelKind::kMassSpring;
  }
  if (!is_auto(node, "integrator") && node.has("integrator")) {
    req.integrator = parse_integrator_kind(node.choice(
        "integrator", {"auto", "explicit_euler", "symplectic_euler", "implicit_euler"}));
  } else if (!node.has("integrator")) {
    req.integrator = IntegratorKind::kSymplecticEuler;
  }
  if (!is_auto(node, "level")) {
    req.level =
        static_cast<int>(node.integer_or("level", req.model == ModelKind::kFem ? 2 : 4, 0, 6));
  }
  if (!is_auto(node, "kernel") && node.has("kernel")) {
    req.kernel = node.choice("kernel", {"auto", "scalar", "simd"}) == "simd" ? KernelKind::kSimd
                                                                             : KernelKind::kScalar;
  }  // not given: chosen too (an automatic selection may take the simd kernel)
  return req;
}

/// Refuses the body when the selection found nothing (names the field to change and its range).
void check_selection(const config::Node& node, const SelectResult& r, const ModelRequest& req,
                     const std::string& table_file, const std::string& dt_text) {
  switch (r.outcome) {
    case SelectOutcome::kChosen:
      break;
    case SelectOutcome::kNoEntry:
      node.fail(is_auto(node, "level")        ? "level"
                : is_auto(node, "model")      ? "model"
                : is_auto(node, "integrator") ? "integrator"
                                              : "kernel",
                "auto: no entry of " + table_file +
                    " matches the fixed fields at a step dividing the world step " + dt_text +
                    " (or every matching entry blew up)");
    case SelectOutcome::kTolerance:
      node.fail("tolerance_pct",
                "value " + fmtg(req.tolerance_pct) +
                    " is below the smallest physical error in the table for this body (" +
                    fmt4(r.most_accurate.error_pct) + " %: " + r.most_accurate.name() +
                    "); allowed range [" + fmt4(r.most_accurate.error_pct) + ", " +
                    fmtg(kToleranceMaxPct) + "]");
    case SelectOutcome::kBudget:
      node.fail("budget_us",
                "value " + fmtg(req.budget_us) + " is below the cheapest entry within tolerance " +
                    fmtg(req.tolerance_pct) + " % (" + r.cheapest_accurate.name() + ": " +
                    fmt1(r.cheapest_accurate.cost_us_median) + " us per world step of " + dt_text +
                    "); allowed range [" + fmt1(r.cheapest_accurate.cost_us_median) + ", " +
                    fmtg(kBudgetMaxUs) + "]");
  }
}

/// The body's parameters with the chosen entry filled in for its auto fields.
DeformableParams chosen_params(const config::Node& node, const ModelChoice& c) {
  YAML::Node y = YAML::Clone(node.raw());
  y.remove("tolerance_pct");
  y.remove("budget_us");
  y.remove("model_table");
  y["model"] = to_string(c.entry.model);
  y["integrator"] = to_string(c.entry.integrator);
  y["level"] = c.entry.level;
  y["kernel"] = to_string(c.entry.kernel);
  if (c.substeps > 1) y["min_substeps"] = c.substeps;
  if (c.entry.mass_scaling_step_s > 0.0) y["mass_scaling_step_s"] = c.entry.mass_scaling_step_s;
  // as in the table, a mass-spring body's springs come from its material (the default one when
  // it gives none), unless it gives the springs themselves
  if (!node.has("edge_stiffness_n_per_m") && !node.has("radial_stiffness_n_per_m3") &&
      !node.has("youngs_modulus_pa") && !node.has("poisson_ratio")) {
    y["youngs_modulus_pa"] = DeformableParams{}.youngs_modulus_pa;
  }
  return load_deformable_params(config::Node(y, node.file(), node.path()));
}

}  // namespace

AutoBody load_deformable_body(const config::Node& node, double physics_dt_s,
                              const std::vector<Plane>& planes) {
  AutoBody out;
  const bool any_auto = node.is_map() && (is_auto(node, "model") || is_auto(node, "integrator") ||
                                          is_auto(node, "level") || is_auto(node, "kernel"));
  if (!any_auto) {
    if (node.is_map()) {
      for (const char* key : {"tolerance_pct", "tolerance_mm", "budget_us", "model_table"}) {
        if (node.has(key)) {
          node.fail(key,
                    "is used only when model, integrator, level or kernel is auto (automatic "
                    "model selection); remove it or set one of them to auto");
        }
      }
    }
    const DeformableParams params = load_deformable_params(node);
    out.model = make_model(params, planes);
    return out;
  }
  for (const char* key : {"mesh_file", "tet_mesh_file"}) {
    if (node.has(key)) {
      node.fail(key,
                "cannot be combined with model, integrator, level or kernel: auto (the speed-"
                "accuracy table is measured on the icospheres and the shipped tetrahedral "
                "balls); give the model explicitly");
    }
  }
  const ModelRequest req = model_request(node, physics_dt_s);
  out.tolerance_pct = req.tolerance_pct;
  out.budget_us = req.budget_us;
  std::string table_file = default_model_table_file();
  if (node.has("model_table")) {
    std::filesystem::path p = node.string("model_table");
    if (p.is_relative()) p = std::filesystem::path(node.file()).parent_path() / p;
    table_file = p.string();
  }
  out.table_file = table_file;
  ModelTable table = load_model_table(table_file);
  const std::string dt_text = ms_text(physics_dt_s);

  // a body whose own stability needs extra sub-steps (a stiffer material than the table's) costs
  // more than predicted: drop that entry and select again while the real cost is over budget
  for (std::size_t attempt = 0; attempt <= table.entries.size(); ++attempt) {
    const SelectResult r = select_model(table, req);
    check_selection(node, r, req, table_file, dt_text);
    const ModelChoice& c = r.choice;
    const DeformableParams params = chosen_params(node, c);
    DeformableModel m = make_model(params, planes);
    // the sub-steps this body needs per entry step against those the table's body took
    const double stab =
        std::max(1.0, static_cast<double>(m.substeps_needed(c.entry.dt_s)) / c.entry.substeps);
    if (stab > 1.0 && c.cost_us_median * stab > req.budget_us) {
      // remove this entry and try the next cheapest
      const TableEntry& e = c.entry;
      table.entries.erase(std::remove_if(table.entries.begin(), table.entries.end(),
                                         [&](const TableEntry& x) {
                                           return x.model == e.model &&
                                                  x.integrator == e.integrator &&
                                                  x.kernel == e.kernel && x.level == e.level &&
                                                  x.dt_s == e.dt_s;
                                         }),
                          table.entries.end());
      if (!table.entries.empty()) continue;
      node.fail("budget_us", "value " + fmtg(req.budget_us) +
                                 " is below what this body costs with the sub-steps its "
                                 "stiffness needs (" +
                                 c.name() + ": " + fmt1(c.cost_us_median * stab) + " us)");
    }
    out.model = std::move(m);
    out.choice = c;
    out.stability_factor = stab;
    out.differs_from_table = differences_from_table(out.model.params);
    return out;
  }
  node.fail("budget_us",
            "no entry of " + table_file + " fits the budget with this body's stiffness");
}

}  // namespace teleop::sim::deformable
