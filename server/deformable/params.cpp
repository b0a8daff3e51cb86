// Parsing and validation of the `deformable:` YAML mapping.
#include <algorithm>
#include <cmath>
#include <set>
#include <string>

#include "server/deformable/deformable.hpp"

namespace teleop::sim::deformable {

const char* to_string(ModelKind kind) {
  switch (kind) {
    case ModelKind::kMassSpring:
      return "mass_spring";
    case ModelKind::kNavierLinear:
      return "navier_linear";
    case ModelKind::kNavierCorotational:
      return "navier_corotational";
    case ModelKind::kFem:
      return "fem";
  }
  return "?";
}

const char* to_string(IntegratorKind kind) {
  switch (kind) {
    case IntegratorKind::kExplicitEuler:
      return "explicit_euler";
    case IntegratorKind::kSymplecticEuler:
      return "symplectic_euler";
    case IntegratorKind::kImplicitEuler:
      return "implicit_euler";
  }
  return "?";
}

// Here rather than in kernel_simd.cpp so that the scene loader alone (the fuzz build) has it; the
// kernel's AVX2 path (kernel_simd.cpp) exists under the same condition and asks this.
bool simd_kernel_vectorised() {
#if defined(__GNUC__) && defined(__x86_64__)
  static const bool yes = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return yes;
#else
  return false;
#endif
}

KernelKind default_kernel(ModelKind model, IntegratorKind integrator) {
  return model == ModelKind::kMassSpring && integrator == IntegratorKind::kSymplecticEuler &&
                 simd_kernel_vectorised()
             ? KernelKind::kSimd
             : KernelKind::kScalar;
}

const char* to_string(KernelKind kind) {
  switch (kind) {
    case KernelKind::kScalar:
      return "scalar";
    case KernelKind::kSimd:
      return "simd";
  }
  return "?";
}

ModelKind parse_model_kind(const std::string& name) {
  for (auto k : {ModelKind::kMassSpring, ModelKind::kNavierLinear, ModelKind::kNavierCorotational,
                 ModelKind::kFem}) {
    if (name == to_string(k)) return k;
  }
  throw config::ConfigError("deformable model '" + name +
                            "' is unknown; choose mass_spring, navier_linear, "
                            "navier_corotational or fem");
}

IntegratorKind parse_integrator_kind(const std::string& name) {
  for (auto k : {IntegratorKind::kExplicitEuler, IntegratorKind::kSymplecticEuler,
                 IntegratorKind::kImplicitEuler}) {
    if (name == to_string(k)) return k;
  }
  throw config::ConfigError("integrator '" + name +
                            "' is unknown; choose explicit_euler, symplectic_euler or "
                            "implicit_euler");
}

namespace {

// The fields of the volumetric model: its tetrahedral mesh and its contact stiffness.
void load_volume_fields(const teleop::config::Node& node, DeformableParams& p) {
  const bool fem = p.model == ModelKind::kFem;
  p.tet_mesh_file = node.string_or("tet_mesh_file", "");
  if (!fem && !p.tet_mesh_file.empty()) node.fail("tet_mesh_file", "is for model fem only");
  if (!p.tet_mesh_file.empty() && !p.mesh_file.empty()) {
    node.fail("tet_mesh_file", "give either mesh_file (filled by gmsh) or tet_mesh_file, not both");
  }
  p.tet_max_edge_m = node.number_or("tet_max_edge_m", 0.0, 0.0, 100.0);
  p.contact_pressure_stiffness_pa_per_m =
      node.number_or("contact_pressure_stiffness_pa_per_m", 0.0, 0.0, 1e15);
  if (!fem && node.has("nodal_pressure")) node.fail("nodal_pressure", "is for model fem only");
  p.nodal_pressure = node.boolean_or("nodal_pressure", true);
  for (const char* key : {"mass_scaling_step_s", "mass_scaling_max_fraction"}) {
    if (!fem && node.has(key)) node.fail(key, "is for model fem only");
  }
  p.mass_scaling_step_s = node.number_or("mass_scaling_step_s", 0.0, 0.0, 1.0);
  p.mass_scaling_max_fraction =
      node.number_or("mass_scaling_max_fraction", p.mass_scaling_max_fraction, 0.0, 0.5);
}

// Model mass_spring: a body that gives its material (youngs_modulus_pa, poisson_ratio) gets its
// springs derived from it (springs_from_material); one that gives springs keeps them; not both.
void load_mass_spring_source(const teleop::config::Node& node, DeformableParams& p) {
  if (p.model != ModelKind::kMassSpring) return;
  const bool material = node.has("youngs_modulus_pa") || node.has("poisson_ratio");
  if (!material) return;
  for (const char* key : {"edge_stiffness_n_per_m", "radial_stiffness_n_per_m3"}) {
    if (node.has(key)) {
      node.fail(key,
                "give a mass-spring body either its material (youngs_modulus_pa, poisson_ratio: "
                "the springs are derived from it, docs/deformable.md \"Mass-spring from a "
                "material\") or its springs (edge_stiffness_n_per_m, radial_stiffness_n_per_m3), "
                "not both");
    }
  }
  p.springs_from_material = true;
}

}  // namespace

namespace {

// The fields of a deformable body's mapping.
const std::set<std::string>& deformable_keys() {
  static const std::set<std::string> keys = {"model",
                                             "integrator",
                                             "kernel",
                                             "level",
                                             "radius_m",
                                             "centre_m",
                                             "mesh_file",
                                             "mesh_scale",
                                             "tet_mesh_file",
                                             "tet_max_edge_m",
                                             "contact_pressure_stiffness_pa_per_m",
                                             "nodal_pressure",
                                             "mass_scaling_step_s",
                                             "mass_scaling_max_fraction",
                                             "mass_kg",
                                             "density_kg_per_m3",
                                             "centre_mass_fraction",
                                             "edge_stiffness_n_per_m",
                                             "radial_stiffness_n_per_m3",
                                             "youngs_modulus_pa",
                                             "poisson_ratio",
                                             "stiffness_damping_s",
                                             "radial_damping_s",
                                             "mass_damping_per_s",
                                             "gravity_mps2",
                                             "contact_frequency_rad_per_s",
                                             "contact_damping_ratio",
                                             "friction",
                                             "cg_max_iterations",
                                             "cg_tolerance",
                                             "sleep_speed_mps",
                                             "sleep_time_s",
                                             "max_speed_mps",
                                             "max_substeps",
                                             "min_substeps"};
  return keys;
}

// model, integrator, kernel and level.
void load_kind_fields(const teleop::config::Node& node, DeformableParams& p) {
  p.model = parse_model_kind(node.choice_or(
      "model", "mass_spring", {"mass_spring", "navier_linear", "navier_corotational", "fem"}));
  const bool fem = p.model == ModelKind::kFem;
  p.integrator = parse_integrator_kind(node.choice_or(
      "integrator", "symplectic_euler", {"explicit_euler", "symplectic_euler", "implicit_euler"}));
  p.kernel = !node.has("kernel") ? default_kernel(p.model, p.integrator)
             : node.choice("kernel", {"scalar", "simd"}) == "simd" ? KernelKind::kSimd
                                                                   : KernelKind::kScalar;
  if (p.kernel == KernelKind::kSimd &&
      (p.model != ModelKind::kMassSpring || p.integrator != IntegratorKind::kSymplecticEuler)) {
    node.fail("kernel",
              "simd is implemented for model mass_spring with integrator symplectic_euler only");
  }
  p.level = fem ? static_cast<int>(node.integer_or("level", 2, 1, teleop::mesh::kMaxBallTetLevel))
                : static_cast<int>(node.integer_or("level", p.level, 0, 6));
#ifdef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
  // fuzz builds only (tests/fuzz): a level-6 body takes 0.2 s to build; level 2 takes 1 ms
  p.level = std::min(p.level, 2);
#endif
}

// The shape: radius, centre, surface mesh and its scale.
void load_shape_fields(const teleop::config::Node& node, DeformableParams& p) {
  p.radius_m = node.number_or("radius_m", p.radius_m, 1e-3, 100.0);
  const auto c =
      node.numbers_or("centre_m", {p.centre_m.x(), p.centre_m.y(), p.centre_m.z()}, -1e4, 1e4);
  if (c.size() != 3) node.fail("centre_m", "must be a list of 3 numbers [x, y, z] in metres");
  p.centre_m = Eigen::Vector3d(c[0], c[1], c[2]);
  p.mesh_file = node.string_or("mesh_file", "");
  p.mesh_scale = node.number_or("mesh_scale", 1.0, 1e-6, 1e6);
}

// Mass, stiffness, material and damping.
void load_material_fields(const teleop::config::Node& node, DeformableParams& p) {
  const bool fem = p.model == ModelKind::kFem;
  if (node.has("mass_kg") && node.has("density_kg_per_m3")) {
    node.fail("density_kg_per_m3", "give either mass_kg or density_kg_per_m3, not both");
  }
  p.mass_kg = node.number_or("mass_kg", p.mass_kg, 1e-4, 1e5);
  if (node.has("density_kg_per_m3")) {
    p.density_kg_per_m3 = node.number("density_kg_per_m3", 1.0, 2.5e4);
  }
  p.centre_mass_fraction =
      node.number_or("centre_mass_fraction", p.centre_mass_fraction, 0.01, 0.9);
  p.edge_stiffness_n_per_m =
      node.number_or("edge_stiffness_n_per_m", p.edge_stiffness_n_per_m, 0.0, 1e7);
  const double radial_default =
      p.model == ModelKind::kMassSpring ? p.radial_stiffness_n_per_m3 : 0.0;
  p.radial_stiffness_n_per_m3 =
      node.number_or("radial_stiffness_n_per_m3", radial_default, 0.0, 1e10);
  p.youngs_modulus_pa = node.number_or("youngs_modulus_pa", p.youngs_modulus_pa, 1.0, 1e10);
  p.poisson_ratio = node.number_or("poisson_ratio", p.poisson_ratio, 0.0, 0.49);
  // model fem: Rayleigh damping beta K + alpha M (alpha relative to the mean velocity); lighter
  // defaults than the surface models' (zeta 0.05 on the default ball's lowest modes)
  p.stiffness_damping_s =
      node.number_or("stiffness_damping_s", fem ? 1e-4 : p.stiffness_damping_s, 0.0, 1.0);
  p.radial_damping_s = node.number_or("radial_damping_s", p.radial_damping_s, 0.0, 1.0);
  p.mass_damping_per_s =
      node.number_or("mass_damping_per_s", fem ? 5.0 : p.mass_damping_per_s, 0.0, 1e3);
}

// Gravity, contact, the implicit solve, sleep and sub-steps.
void load_solver_fields(const teleop::config::Node& node, DeformableParams& p) {
  const auto g = node.numbers_or(
      "gravity_mps2", {p.gravity_mps2.x(), p.gravity_mps2.y(), p.gravity_mps2.z()}, -100.0, 100.0);
  if (g.size() != 3) node.fail("gravity_mps2", "must be a list of 3 numbers [m/s^2]");
  p.gravity_mps2 = Eigen::Vector3d(g[0], g[1], g[2]);
  p.contact_frequency_rad_per_s =
      node.number_or("contact_frequency_rad_per_s", p.contact_frequency_rad_per_s, 1.0, 1e6);
  p.contact_damping_ratio =
      node.number_or("contact_damping_ratio", p.contact_damping_ratio, 0.0, 10.0);
  p.friction = node.boolean_or("friction", p.friction);
  p.cg_max_iterations =
      static_cast<int>(node.integer_or("cg_max_iterations", p.cg_max_iterations, 1, 10000));
  p.cg_tolerance = node.number_or("cg_tolerance", p.cg_tolerance, 1e-14, 1e-1);
  p.sleep_speed_mps = node.number_or("sleep_speed_mps", p.sleep_speed_mps, 0.0, 1.0);
  p.sleep_time_s = node.number_or("sleep_time_s", p.sleep_time_s, 0.0, 1e3);
  p.max_speed_mps = node.number_or("max_speed_mps", p.max_speed_mps, 1e-3, 1e6);
  p.max_substeps = static_cast<int>(node.integer_or("max_substeps", p.max_substeps, 1, 10000));
  p.min_substeps = static_cast<int>(node.integer_or("min_substeps", p.min_substeps, 1, 10000));
}

}  // namespace

DeformableParams load_deformable_params(const teleop::config::Node& node) {
  if (!node.is_map()) {
    throw config::ConfigError(node.file() + ": field '" + node.path() +
                              "' must be a mapping of deformable-body parameters");
  }
  node.reject_unknown_keys(deformable_keys());
  DeformableParams p;
  load_kind_fields(node, p);
  load_shape_fields(node, p);
  load_volume_fields(node, p);
  load_material_fields(node, p);
  load_solver_fields(node, p);
  load_mass_spring_source(node, p);
  if (p.model == ModelKind::kMassSpring && !p.springs_from_material &&
      p.edge_stiffness_n_per_m <= 0.0 && p.radial_stiffness_n_per_m3 <= 0.0) {
    node.fail("edge_stiffness_n_per_m",
              "a mass-spring body needs edge_stiffness_n_per_m > 0 or "
              "radial_stiffness_n_per_m3 > 0");
  }
  return p;
}

}  // namespace teleop::sim::deformable
