#pragma once
// Automatic model: `model: auto`, `integrator: auto`, `level: auto` (and `kernel: auto`) in a
// scene's deformable body pick, from the speed-accuracy table that `teleop_bench deformable`
// measured on this machine (deploy/data/deformable.csv), the cheapest combination whose
// error stays within the body's `tolerance_mm` and whose cost per world step fits `budget_us`.
// Runs once at load (allocates; never in the loop). docs/deformable.md, "Automatic model".
//
// Error [mm] = dynamic error + shape error:
//  - dynamic: the table's `error` column, i.e. the RMS over 0-0.1 s (samples every 1 ms) of the
//    radial displacement of icosahedron vertex 5 after a 5 mm cos^2 bump is released, against the
//    same model's converged reference (level 6, dt 62.5 us, symplectic Euler): the error of the
//    mesh level, the step and the integrator in the motion, for the default material;
//  - shape: the largest distance between the level's flat triangles and the sphere they stand
//    for (icosphere_shape_error_m, scaled to the body's radius): what the tip touches. Without it
//    a 42-node level-1 ball (9.6 mm off the sphere) would look as good as level 4, because the
//    mass-spring model's motion converges fast in the level.
// Cost: n x (the entry's median step), n = world step / entry step (an integer; n > 1 means
// n accuracy sub-steps per world step, params.min_substeps).
//
//   AutoBody b = load_deformable_body(scene.at("deformables").at(0).at("body"), 1e-3, planes);
//   // b.choice is set when anything was `auto`; b.model is built either way
#include <array>
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
  int level = 4;
  double dt_s = 1e-3;           ///< the step the entry was measured at [s]
  double step_us_median = 0.0;  ///< wall time of one step, median [us]
  double step_us_p99 = 0.0;     ///< [us]
  double error_m = 0.0;         ///< see the file comment; +inf when the run blew up [m]
};

struct ModelTable {
  std::string file;  ///< where it was read from (messages)
  std::vector<TableEntry> entries;
};

/// Parses the CSV text (header model,integrator,level,dt_s,step_us_median,step_us_p99,error
/// and an optional kernel column). @throws config::ConfigError naming the file and the line.
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
  double tolerance_mm = 0.0;   ///< largest accepted error [mm], > 0
  double budget_us = 0.0;      ///< largest accepted cost per world step (median) [us], > 0
  double physics_dt_s = 1e-3;  ///< the world's step [s]
  /// Shape error of each icosphere level 0-6 for this body [mm] (icosphere_shape_error_m); zero:
  /// the table's dynamic error alone.
  std::array<double, 7> shape_error_mm{};
};

/// Largest distance between the flat triangles of make_icosphere(level, radius_m) and the sphere
/// of that radius [m] (r minus the smallest distance from the centre to a triangle's plane).
double icosphere_shape_error_m(int level, double radius_m);

/// A table entry as it would run in the world.
struct ModelChoice {
  TableEntry entry;
  int substeps = 1;               ///< entry steps per world step (params.min_substeps)
  double cost_us_median = 0.0;    ///< substeps x entry median [us]
  double cost_us_p99 = 0.0;       ///< substeps x entry p99 [us] (an upper guide, not a percentile)
  double error_mm = 0.0;          ///< dynamic_error_mm + shape_error_mm [mm]
  double dynamic_error_mm = 0.0;  ///< the entry's error column [mm]
  double shape_error_mm = 0.0;    ///< the level's shape error for this body [mm]
  /// "mass_spring symplectic_euler simd level 4, 1 x 1 ms": the combination, short.
  std::string name() const;
};

enum class SelectOutcome : std::uint8_t {
  kChosen = 0,
  kNoEntry = 1,    ///< no finite entry matches the fixed fields at a step dividing the world's
  kTolerance = 2,  ///< entries match, none is within tolerance_mm
  kBudget = 3,     ///< entries are within tolerance, none fits budget_us
};

struct SelectResult {
  SelectOutcome outcome = SelectOutcome::kNoEntry;
  ModelChoice choice;             ///< kChosen: the cheapest (ties: smaller error, then table order)
  int matching = 0;               ///< entries matching the fixed fields and the step
  int within_tolerance = 0;       ///< of those, within tolerance_mm
  ModelChoice most_accurate;      ///< smallest error among the matching ones (kTolerance)
  ModelChoice cheapest_accurate;  ///< cheapest among those within tolerance (kBudget)
};

/// The selection itself: pure, no I/O. Entries that blew up, whose step does not divide the
/// world's step (or exceeds it) or that contradict a fixed field are not candidates.
SelectResult select_model(const ModelTable& table, const ModelRequest& request);

/// A body built from a `deformable:` mapping, with the automatic choice when there was one.
struct AutoBody {
  DeformableModel model;
  std::optional<ModelChoice> choice;
  double tolerance_mm = 0.0;
  double budget_us = 0.0;
  std::string table_file;
  /// Parameters that differ from the material the table was measured with (empty: none): the
  /// predicted error then is an extrapolation.
  std::vector<std::string> differs_from_table;
  /// Sub-steps the body's own stability adds per entry step (1 for the table's material).
  int stability_substeps = 1;
  /// One line (< 128 characters) for the event log: the choice, its predicted cost and error.
  std::string summary() const;
  /// The full report printed at load (several lines).
  std::string report() const;
};

/// Reads a `deformable:` mapping and builds the body. Without `auto` it is exactly
/// make_model(make_mesh_for(load_deformable_params(node)), ...). With `model`, `integrator`,
/// `level` or `kernel` set to `auto` it also reads `tolerance_mm` (0, 1000] and `budget_us`
/// (0, 1e6] (both required) and optional `model_table` (a CSV path, relative to the scene
/// file; default default_model_table_file()), selects with select_model for physics_dt_s and
/// fills in the choice (kernel: chosen unless the scene fixes it). If the built body needs
/// stability sub-steps the table did not have (a stiffer material), the cost is recomputed and
/// the next candidate tried while over budget.
/// @throws config::ConfigError naming file, field, value and range (exit 2 in executables):
/// tolerance_mm <= 0, budget_us below the cheapest entry within tolerance (named with its
/// cost), a tolerance no entry meets (the smallest error named), auto with mesh_file,
/// tolerance_mm / budget_us without auto, a missing or malformed table.
/// True if any of model, integrator, level or kernel is `auto` in this body section.
bool has_auto_field(const teleop::config::Node& node);

AutoBody load_deformable_body(const teleop::config::Node& node, double physics_dt_s,
                              const std::vector<Plane>& planes);

}  // namespace teleop::sim::deformable
