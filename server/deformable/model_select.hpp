#pragma once
// Automatic model: `model: auto`, `integrator: auto`, `level: auto` (and `kernel: auto`) in a
// scene's deformable body pick, from the speed-accuracy table that `teleop_bench deformable`
// measured on this machine (deploy/data/deformable.csv), the cheapest combination whose
// physical error stays within the body's `tolerance_pct` and whose cost per world step fits
// `budget_us`. Runs once at load (allocates; never in the loop). docs/deformable.md, "Automatic
// model".
//
// Physical error [%] = the table's `error_pct`: the largest |error| of the entry against physics,
// for the foam ball (E 6000 Pa, nu 0.3, 2 kg, radius 0.25 m) every model derives its parameters
// from: Lamb's S2, T2 and S0 frequencies of the free ball, and the force of the tip pressing the
// ball on the floor 5 mm deep under its weight against the converged CalculiX ball.
// Cost: n x (the entry's median cost per world step, the body's stability sub-steps included),
// n = world step / entry step (an integer; n > 1 means n accuracy sub-steps, params.min_substeps).
//
//   AutoBody b = load_deformable_body(scene.at("deformables").at(0).at("body"), 1e-3, planes);
//   // b.choice is set when anything was `auto`; b.model is built either way
#include <optional>
#include <string>
#include <vector>

#include "server/deformable/deformable.hpp"

namespace teleop::sim::deformable {

/// One row of the table written by `teleop_bench deformable` (deformable.csv).
struct TableEntry {
  ModelKind model = ModelKind::kMassSpring;
  IntegratorKind integrator = IntegratorKind::kSymplecticEuler;
  KernelKind kernel = KernelKind::kScalar;
  int level = 4;       ///< icosphere level, or the shipped tet ball's (model fem)
  double dt_s = 1e-3;  ///< the world step the entry was measured at [s]
  int substeps = 1;    ///< stability sub-steps the body took per world step [-]
  /// Model fem: the mass scaling's stable step the entry ran with [s] (0: none;
  /// params.mass_scaling_step_s)
  double mass_scaling_step_s = 0.0;
  double step_us_median = 0.0;  ///< wall time of one world step, sub-steps included, median [us]
  double step_us_p99 = 0.0;     ///< [us]
  /// Physical error: the largest |error| of the quantities below [%]; +inf when a quantity could
  /// not be measured (the run blew up, or the mode did not vibrate).
  double error_pct = 0.0;
  /// Signed errors of the quantities [%] (NaN when the table has no such column).
  double s2_pct = 0.0, t2_pct = 0.0, s0_pct = 0.0, press_pct = 0.0;
};

struct ModelTable {
  std::string file;  ///< where it was read from (messages)
  std::vector<TableEntry> entries;
};

/// Parses the CSV text: the header must name model, integrator, level, dt_s, step_us_median,
/// step_us_p99 and error_pct; kernel, substeps, lamb_s2_pct, lamb_t2_pct, lamb_s0_pct and
/// press_5mm_pct are read when present; other columns are ignored. Rows of the peers measured
/// beside ours (model bullet_fem) are skipped: they are for the chart, never a candidate.
/// @throws config::ConfigError naming the file and the line (a table of the former format, with
/// `error` in metres and no `error_pct`, is refused saying so).
ModelTable parse_model_table(const std::string& csv_text, const std::string& file);
/// Reads and parses a table file. @throws config::ConfigError (missing file: says how to make it).
ModelTable load_model_table(const std::string& file);
/// The table shipped with the repository: <source>/deploy/data/deformable.csv.
std::string default_model_table_file();

/// What a scene asks for: fixed fields (set) and automatic ones (nullopt).
struct ModelRequest {
  std::optional<ModelKind> model;
  std::optional<IntegratorKind> integrator;
  std::optional<int> level;
  std::optional<KernelKind> kernel;
  double tolerance_pct = 0.0;  ///< largest accepted physical error [%], > 0
  double budget_us = 0.0;      ///< largest accepted cost per world step (median) [us], > 0
  double physics_dt_s = 1e-3;  ///< the world's step [s]
};

/// A table entry as it would run in the world.
struct ModelChoice {
  TableEntry entry;
  int substeps = 1;             ///< entry steps per world step (params.min_substeps)
  double cost_us_median = 0.0;  ///< substeps x entry median [us]
  double cost_us_p99 = 0.0;     ///< substeps x entry p99 [us] (an upper guide, not a percentile)
  double error_pct = 0.0;       ///< the entry's physical error [%]
  /// "mass_spring symplectic_euler simd level 4, 1 x 1 ms": the combination, short.
  std::string name() const;
};

enum class SelectOutcome : std::uint8_t {
  kChosen = 0,
  kNoEntry = 1,    ///< no finite entry matches the fixed fields at a step dividing the world's
  kTolerance = 2,  ///< entries match, none is within tolerance_pct
  kBudget = 3,     ///< entries are within tolerance, none fits budget_us
};

struct SelectResult {
  SelectOutcome outcome = SelectOutcome::kNoEntry;
  ModelChoice choice;             ///< kChosen: the cheapest (ties: smaller error, then table order)
  int matching = 0;               ///< entries matching the fixed fields and the step
  int within_tolerance = 0;       ///< of those, within tolerance_pct
  ModelChoice most_accurate;      ///< smallest error among the matching ones (kTolerance)
  ModelChoice cheapest_accurate;  ///< cheapest among those within tolerance (kBudget)
};

/// The selection itself: pure, no I/O. Entries that blew up (error inf), whose step does not
/// divide the world's step (or exceeds it) or that contradict a fixed field are not candidates.
SelectResult select_model(const ModelTable& table, const ModelRequest& request);

/// A body built from a `deformable:` mapping, with the automatic choice when there was one.
struct AutoBody {
  DeformableModel model;
  std::optional<ModelChoice> choice;
  double tolerance_pct = 0.0;
  double budget_us = 0.0;
  std::string table_file;
  /// Parameters that differ from the material the table was measured with (empty: none): the
  /// predicted error then is an extrapolation.
  std::vector<std::string> differs_from_table;
  /// The factor the body's own stability sub-steps add to the entry's cost: the sub-steps it
  /// needs per entry step over those the table's body took (1 for the table's material).
  double stability_factor = 1.0;
  /// One line (< 128 characters) for the event log: the choice, its predicted cost and error.
  std::string summary() const;
  /// The full report printed at load (several lines).
  std::string report() const;
};

/// True if any of model, integrator, level or kernel is `auto` in this body section.
bool has_auto_field(const teleop::config::Node& node);

/// Reads a `deformable:` mapping and builds the body. Without `auto` it is exactly
/// make_model(load_deformable_params(node), planes). With `model`, `integrator`, `level` or
/// `kernel` set to `auto` it also reads `tolerance_pct` (0, 1000] and `budget_us` (0, 1e6] (both
/// required) and optional `model_table` (a CSV path, relative to the scene file; default
/// default_model_table_file()), selects with select_model for physics_dt_s and fills in the choice
/// (kernel: chosen unless the scene fixes it). The body's parameters come from its material
/// (youngs_modulus_pa, poisson_ratio, mass_kg or density_kg_per_m3, defaults the foam's) for every
/// model, as in the table, unless it gives mass-spring springs. If the built body needs more
/// stability sub-steps than the table's (a stiffer material), the cost is scaled and the next
/// candidate tried while over budget.
/// @throws config::ConfigError naming file, field, value and range (exit 2 in executables):
/// tolerance_pct <= 0, tolerance_mm (replaced by tolerance_pct), budget_us below the cheapest
/// entry within tolerance (named with its cost), a tolerance no entry meets (the smallest error
/// named), auto with mesh_file or tet_mesh_file, tolerance_pct / budget_us without auto, a
/// missing or malformed table.
AutoBody load_deformable_body(const teleop::config::Node& node, double physics_dt_s,
                              const std::vector<Plane>& planes);

}  // namespace teleop::sim::deformable
