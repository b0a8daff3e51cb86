#include "server/deformable/body_params.hpp"

namespace teleop::sim::deformable {

using config::FieldParam;
using P = DeformableParams;

namespace {

/// The body's shape and mass.
std::vector<FieldParam<P>> shape_and_mass() {
  return {
      {.key = "radius_m",
       .unit = "m",
       .help = "icosphere radius",
       .lo = 1e-3,
       .hi = 100.0,
       .number = TELEOP_FIELD(P, radius_m)},
      {.key = "centre_m",
       .unit = "m",
       .help = "icosphere centre; with a mesh file, its offset",
       .lo = -1e4,
       .hi = 1e4,
       .point = TELEOP_FIELD(P, centre_m)},
      {.key = "mesh_scale",
       .unit = "-",
       .help = "mesh_file or tet_mesh_file units to metres",
       .lo = 1e-6,
       .hi = 1e6,
       .number = TELEOP_FIELD(P, mesh_scale)},
      {.key = "tet_max_edge_m",
       .unit = "m",
       .help = "model fem with mesh_file: the closed surface is filled with tetrahedra up to "
               "this edge by gmsh at load (0: a sixth of the cube root of the volume)",
       .hi = 100.0,
       .number = TELEOP_FIELD(P, tet_max_edge_m)},
      {.key = "mass_kg",
       .unit = "kg",
       .help = "total mass (or density_kg_per_m3 times the enclosed volume; not both)",
       .lo = 1e-4,
       .hi = 1e5,
       .number = TELEOP_FIELD(P, mass_kg)},
      {.key = "centre_mass_fraction",
       .unit = "-",
       .help = "mass_spring with radial springs: share of the mass carried by the centre node",
       .lo = 0.01,
       .hi = 0.9,
       .number = TELEOP_FIELD(P, centre_mass_fraction)},
  };
}

/// Stiffness, material and damping.
std::vector<FieldParam<P>> material() {
  return {
      {.key = "edge_stiffness_n_per_m",
       .unit = "N/m",
       .help = "mass_spring: each edge spring (refused with the material given)",
       .hi = 1e7,
       .number = TELEOP_FIELD(P, edge_stiffness_n_per_m)},
      {.key = "youngs_modulus_pa",
       .unit = "Pa",
       .help = "Young's modulus E: the Navier models and fem use it; a mass_spring body that "
               "gives it gets its springs derived from it (docs/deformable.md)",
       .lo = 1.0,
       .hi = 1e10,
       .number = TELEOP_FIELD(P, youngs_modulus_pa)},
      {.key = "poisson_ratio",
       .unit = "-",
       .help = "Poisson's ratio nu (see youngs_modulus_pa)",
       .hi = 0.49,
       .number = TELEOP_FIELD(P, poisson_ratio)},
      {.key = "radial_damping_s",
       .unit = "s",
       .help = "mass_spring: damper of each radial spring, c_i = this * k_i",
       .hi = 1.0,
       .number = TELEOP_FIELD(P, radial_damping_s)},
  };
}

/// Loads, contact with the planes, the fem body's contact and mass scaling.
std::vector<FieldParam<P>> loads_and_contact() {
  return {
      {.key = "gravity_mps2",
       .unit = "m/s^2",
       .help = "gravity on the body",
       .lo = -100.0,
       .hi = 100.0,
       .point = TELEOP_FIELD(P, gravity_mps2)},
      {.key = "contact_frequency_rad_per_s",
       .unit = "rad/s",
       .help = "surface models: node-plane penalty k_i = m_i w^2",
       .lo = 1.0,
       .hi = 1e6,
       .number = TELEOP_FIELD(P, contact_frequency_rad_per_s)},
      {.key = "contact_damping_ratio",
       .unit = "-",
       .help = "surface models: node-plane damping c_i = 2 zeta m_i w",
       .hi = 10.0,
       .number = TELEOP_FIELD(P, contact_damping_ratio)},
      {.key = "friction",
       .help = "Coulomb friction with the planes' coefficients",
       .flag = TELEOP_FIELD(P, friction)},
      {.key = "contact_pressure_stiffness_pa_per_m",
       .unit = "Pa/m",
       .help = "model fem: contact of the surface with planes and the tip as pressure per depth "
               "(node spring = this x node area, implicit per node); 0: 1000 E / (1 - nu^2) / "
               "(cube root of the volume)",
       .hi = 1e15,
       .number = TELEOP_FIELD(P, contact_pressure_stiffness_pa_per_m)},
      {.key = "mass_scaling_step_s",
       .unit = "s",
       .help = "model fem: raise the inertial masses of the nodes that limit the stable step (the "
               "fewest grams; gravity and weight unchanged) until it is at least this; 0: off "
               "(docs/deformable.md, \"Mass scaling\"; default.yaml: 0.001)",
       .hi = 1.0,
       .number = TELEOP_FIELD(P, mass_scaling_step_s)},
      {.key = "mass_scaling_max_fraction",
       .unit = "-",
       .help = "model fem: the most mass the scaling may add, as a fraction of the body's; "
               "needing more is refused",
       .hi = 0.5,
       .number = TELEOP_FIELD(P, mass_scaling_max_fraction)},
  };
}

/// The implicit solve, sleep, fault detection and sub-steps.
std::vector<FieldParam<P>> solver() {
  return {
      {.key = "cg_max_iterations",
       .help = "implicit_euler: most conjugate-gradient iterations per step",
       .lo = 1.0,
       .hi = 10000.0,
       .integer = TELEOP_FIELD(P, cg_max_iterations)},
      {.key = "cg_tolerance",
       .unit = "-",
       .help = "implicit_euler: relative residual at which the solve stops early",
       .lo = 1e-14,
       .hi = 0.1,
       .number = TELEOP_FIELD(P, cg_tolerance)},
      {.key = "sleep_speed_mps",
       .unit = "m/s",
       .help = "a node slower than this is still",
       .hi = 1.0,
       .number = TELEOP_FIELD(P, sleep_speed_mps)},
      {.key = "sleep_time_s",
       .unit = "s",
       .help = "a body still and unloaded this long sleeps",
       .hi = 1e3,
       .number = TELEOP_FIELD(P, sleep_time_s)},
      {.key = "max_speed_mps",
       .unit = "m/s",
       .help = "a node faster than this is a blow-up (a fault)",
       .lo = 1e-3,
       .hi = 1e6,
       .number = TELEOP_FIELD(P, max_speed_mps)},
      {.key = "max_substeps",
       .help = "most sub-steps one step may take when dt exceeds the body's largest stable step "
               "(docs/deformable.md, \"Automatic step\")",
       .lo = 1.0,
       .hi = 10000.0,
       .integer = TELEOP_FIELD(P, max_substeps)},
      {.key = "min_substeps",
       .help = "at least this many equal sub-steps per step, for accuracy (the automatic model "
               "sets it)",
       .lo = 1.0,
       .hi = 10000.0,
       .integer = TELEOP_FIELD(P, min_substeps)},
  };
}

}  // namespace

const std::vector<FieldParam<P>>& body_field_params() {
  static const std::vector<FieldParam<P>> table = [] {
    std::vector<FieldParam<P>> t;
    for (auto part : {shape_and_mass(), material(), loads_and_contact(), solver()}) {
      t.insert(t.end(), part.begin(), part.end());
    }
    return t;
  }();
  return table;
}

}  // namespace teleop::sim::deformable
