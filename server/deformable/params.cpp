// Parsing and validation of the `deformable:` YAML mapping.
#include <algorithm>
#include <cmath>
#include <set>
#include <string>

#include "server/deformable/body_params.hpp"
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

// The fields only the volumetric model takes: its tetrahedral mesh, nodal pressure, mass scaling.
void load_volume_fields(const teleop::config::Node& node, DeformableParams& p) {
  const bool fem = p.model == ModelKind::kFem;
  p.tet_mesh_file = node.string_or("tet_mesh_file", "");
  if (!fem && !p.tet_mesh_file.empty()) node.fail("tet_mesh_file", "is for model fem only");
  if (!p.tet_mesh_file.empty() && !p.mesh_file.empty()) {
    node.fail("tet_mesh_file", "give either mesh_file (filled by gmsh) or tet_mesh_file, not both");
  }
  if (!fem && node.has("nodal_pressure")) node.fail("nodal_pressure", "is for model fem only");
  p.nodal_pressure = node.boolean_or("nodal_pressure", true);
  for (const char* key : {"mass_scaling_step_s", "mass_scaling_max_fraction"}) {
    if (!fem && node.has(key)) node.fail(key, "is for model fem only");
  }
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

// The fields of a deformable body's mapping: the table's and those read here.
std::set<std::string> deformable_keys() {
  return config::field_keys(body_field_params(),
                            {"model", "integrator", "kernel", "level", "mesh_file", "tet_mesh_file",
                             "nodal_pressure", "density_kg_per_m3", "radial_stiffness_n_per_m3",
                             "stiffness_damping_s", "mass_damping_per_s"});
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

// Density, and the fields whose default depends on the model: radial springs, Rayleigh damping.
void load_material_fields(const teleop::config::Node& node, DeformableParams& p) {
  const bool fem = p.model == ModelKind::kFem;
  if (node.has("mass_kg") && node.has("density_kg_per_m3")) {
    node.fail("density_kg_per_m3", "give either mass_kg or density_kg_per_m3, not both");
  }
  if (node.has("density_kg_per_m3")) {
    p.density_kg_per_m3 = node.number("density_kg_per_m3", 1.0, 2.5e4);
  }
  const double radial_default =
      p.model == ModelKind::kMassSpring ? p.radial_stiffness_n_per_m3 : 0.0;
  p.radial_stiffness_n_per_m3 =
      node.number_or("radial_stiffness_n_per_m3", radial_default, 0.0, 1e10);
  // model fem: Rayleigh damping beta K + alpha M (alpha relative to the mean velocity); lighter
  // defaults than the surface models' (zeta 0.05 on the default ball's lowest modes)
  p.stiffness_damping_s =
      node.number_or("stiffness_damping_s", fem ? 1e-4 : p.stiffness_damping_s, 0.0, 1.0);
  p.mass_damping_per_s =
      node.number_or("mass_damping_per_s", fem ? 5.0 : p.mass_damping_per_s, 0.0, 1e3);
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
  p.mesh_file = node.string_or("mesh_file", "");
  load_volume_fields(node, p);
  config::read_fields(node, body_field_params(), p);
  load_material_fields(node, p);
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
