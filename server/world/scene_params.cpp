#include "server/world/scene_params.hpp"

#include <stdexcept>

#include "server/deformable/body_params.hpp"
#include "server/robot/ik_params.hpp"
#include "server/world/world_model.hpp"

namespace teleop::sim {

using config::FieldParam;
using W = WorldModel;

const std::vector<FieldParam<W>>& world_box_params() {
  static const std::vector<FieldParam<W>> t = {
      {.key = "min_m",
       .unit = "m",
       .help = "lower corner of the world box: every object starts inside it and the command "
               "workspace lies inside it; each below max_m's",
       .lo = -1000.0,
       .hi = 1000.0,
       .point = TELEOP_FIELD(W, world_min_m)},
      {.key = "max_m",
       .unit = "m",
       .help = "upper corner of the world box",
       .lo = -1000.0,
       .hi = 1000.0,
       .point = TELEOP_FIELD(W, world_max_m)},
  };
  return t;
}

const std::vector<FieldParam<W>>& physics_params() {
  static const std::vector<FieldParam<W>> t = {
      {.key = "rate_hz",
       .unit = "Hz",
       .help = "physics rate, and at least what the scene's stability needs (refused at load "
               "otherwise); teleop_server --rate overrides it",
       .lo = 10.0,
       .hi = 20000.0,
       .number = TELEOP_FIELD(W, physics_rate_hz)},
      {.key = "visual_rate_hz",
       .unit = "Hz",
       .help = "mesh frame rate",
       .lo = 1.0,
       .hi = 240.0,
       .number = TELEOP_FIELD(W, visual_rate_hz)},
      {.key = "gravity_mps2",
       .unit = "m/s^2",
       .help = "gravity",
       .lo = -100.0,
       .hi = 100.0,
       .point = TELEOP_FIELD(W, gravity_mps2)},
  };
  return t;
}

const std::vector<FieldParam<W>>& command_params() {
  static const std::vector<FieldParam<W>> t = {
      {.key = "timeout_s",
       .unit = "s",
       .help = "watchdog: the slave holds after this long without a valid command; "
               "teleop_server --command-timeout overrides it",
       .lo = 0.001,
       .hi = 10.0,
       .number = TELEOP_FIELD(W, command_timeout_s)},
      {.key = "workspace_min_m",
       .unit = "m",
       .help = "commands outside [workspace_min_m, workspace_max_m] are rejected; each below "
               "workspace_max_m's, inside the world box",
       .lo = -100.0,
       .hi = 100.0,
       .point = TELEOP_FIELD(W, workspace_min_m)},
      {.key = "workspace_max_m",
       .unit = "m",
       .help = "upper corner of the command workspace",
       .lo = -100.0,
       .hi = 100.0,
       .point = TELEOP_FIELD(W, workspace_max_m)},
  };
  return t;
}

const std::vector<FieldParam<W>>& tool_params() {
  static const std::vector<FieldParam<W>> t = {
      {.key = "mass_kg",
       .unit = "kg",
       .help = "tool mass",
       .lo = 1e-3,
       .hi = 100.0,
       .number = TELEOP_FIELD(W, tool.mass_kg)},
      {.key = "radius_m",
       .unit = "m",
       .help = "tool (tip) sphere radius",
       .lo = 1e-3,
       .hi = 1.0,
       .number = TELEOP_FIELD(W, tool.radius_m)},
      {.key = "kp_n_per_m",
       .unit = "N/m",
       .help = "stiffness K_ps of the PD tracking the command (a master's K_ps overrides it; "
               "the server clamps what the tool cannot hold at its rate)",
       .hi = 1e6,
       .number = TELEOP_FIELD(W, tool.kp_n_per_m)},
      {.key = "kd_ns_per_m",
       .unit = "N s/m",
       .help = "damping of the PD tracking the command",
       .hi = 1e4,
       .number = TELEOP_FIELD(W, tool.kd_ns_per_m)},
      {.key = "kp_rot_nm_per_rad",
       .unit = "N m/rad",
       .help = "rotational PD stiffness",
       .hi = 1e4,
       .number = TELEOP_FIELD(W, tool.kp_rot_nm_per_rad)},
      {.key = "kd_rot_nms_per_rad",
       .unit = "N m s/rad",
       .help = "rotational PD damping",
       .hi = 1e3,
       .number = TELEOP_FIELD(W, tool.kd_rot_nms_per_rad)},
      {.key = "linear_damping_ns_per_m",
       .unit = "N s/m",
       .help = "viscous damping to the world",
       .hi = 1e4,
       .number = TELEOP_FIELD(W, tool.linear_damping_ns_per_m)},
      {.key = "max_force_n",
       .unit = "N",
       .help = "saturation of the PD force",
       .lo = 0.1,
       .hi = 1e5,
       .number = TELEOP_FIELD(W, tool.max_force_n)},
      {.key = "gravity_compensation",
       .help = "the PD cancels m g",
       .flag = TELEOP_FIELD(W, tool.gravity_compensation)},
      {.key = "start_position_m",
       .unit = "m",
       .help = "initial position, inside the workspace",
       .lo = -100.0,
       .hi = 100.0,
       .point = TELEOP_FIELD(W, tool_start_m)},
  };
  return t;
}

const std::vector<FieldParam<Plane>>& plane_params() {
  static const std::vector<FieldParam<Plane>> t = {
      {.key = "offset_m",
       .unit = "m",
       .help = "normal . x = offset_m on the surface (normal: any length, normalised)",
       .lo = -100.0,
       .hi = 100.0,
       .number = TELEOP_FIELD(Plane, offset_m)},
      {.key = "stiffness_n_per_m",
       .unit = "N/m",
       .help = "penalty stiffness",
       .lo = 1.0,
       .hi = 1e8,
       .number = TELEOP_FIELD(Plane, stiffness_n_per_m)},
      {.key = "damping_ns_per_m",
       .unit = "N s/m",
       .help = "penalty damping (compression only)",
       .hi = 1e6,
       .number = TELEOP_FIELD(Plane, damping_ns_per_m)},
      {.key = "friction",
       .unit = "-",
       .help = "Coulomb coefficient",
       .hi = 5.0,
       .number = TELEOP_FIELD(Plane, friction)},
  };
  return t;
}

const std::vector<FieldParam<collision::TipContactParams>>& tip_contact_params() {
  using C = collision::TipContactParams;
  static const std::vector<FieldParam<C>> t = {
      {.key = "stiffness_n_per_m",
       .unit = "N/m",
       .help = "k of the proxy spring F = k x (docs/collision.md)",
       .lo = 1.0,
       .hi = 1e7,
       .number = TELEOP_FIELD(C, stiffness_n_per_m)},
      {.key = "damping_ns_per_m",
       .unit = "N s/m",
       .help = "normal contact damping b",
       .hi = 1e5,
       .number = TELEOP_FIELD(C, damping_ns_per_m)},
      {.key = "damping_ramp_m",
       .unit = "m",
       .help = "the damping grows linearly to b over this depth",
       .hi = 0.1,
       .number = TELEOP_FIELD(C, damping_ramp_m)},
      {.key = "friction_static",
       .unit = "-",
       .help = "Coulomb static coefficient mu_s between the tip and the body",
       .hi = 5.0,
       .number = TELEOP_FIELD(C, friction_static)},
      {.key = "friction_kinetic",
       .unit = "-",
       .help = "Coulomb kinetic coefficient mu_k, at most friction_static",
       .hi = 5.0,
       .number = TELEOP_FIELD(C, friction_kinetic)},
      {.key = "max_force_n",
       .unit = "N",
       .help = "saturation of the contact force (0: none)",
       .hi = 1e5,
       .number = TELEOP_FIELD(C, max_force_n)},
      {.key = "patch_radius_m",
       .unit = "m",
       .help = "radius of the node patch that shares the reaction (about the tip radius)",
       .hi = 1.0,
       .number = TELEOP_FIELD(C, patch_radius_m)},
      {.key = "patch_blend",
       .unit = "-",
       .help = "share of the reaction spread over the patch, the rest to the anchor triangle's "
               "corners (0: the paper's three-vertex push)",
       .hi = 1.0,
       .number = TELEOP_FIELD(C, patch_blend)},
      {.key = "node_stiffness_n_per_m",
       .unit = "N/m",
       .help = "penalty stiffness of each surface node inside the tip sphere (0: the paper's "
               "single-point proxy only)",
       .hi = 1e6,
       .number = TELEOP_FIELD(C, node_stiffness_n_per_m)},
      {.key = "node_damping_ns_per_m",
       .unit = "N s/m",
       .help = "damping of each node penalty (compression only, ramped in)",
       .hi = 1e4,
       .number = TELEOP_FIELD(C, node_damping_ns_per_m)},
      {.key = "node_reference_area_m2",
       .unit = "m^2",
       .help = "the node area node_stiffness_n_per_m and node_damping_ns_per_m are for: each "
               "node's penalty is scaled by its area over this (0: the same on every node); the "
               "default is the level-4 sphere's mean node area",
       .hi = 1.0,
       .number = TELEOP_FIELD(C, node_reference_area_m2)},
  };
  return t;
}

template <class S>
const FieldParam<S>& scene_param(const std::vector<FieldParam<S>>& table, const std::string& key) {
  for (const FieldParam<S>& f : table) {
    if (f.key == key) return f;
  }
  throw std::out_of_range("no scene parameter '" + key + "'");
}

template const FieldParam<W>& scene_param(const std::vector<FieldParam<W>>&, const std::string&);
template const FieldParam<Plane>& scene_param(const std::vector<FieldParam<Plane>>&,
                                              const std::string&);
template const FieldParam<collision::TipContactParams>& scene_param(
    const std::vector<FieldParam<collision::TipContactParams>>&, const std::string&);

std::string scene_params_markdown() {
  const WorldModel w;
  std::string md = config::fields_markdown_header();
  md += config::fields_markdown_rows("world.", world_box_params(), w);
  md += config::fields_markdown_rows("physics.", physics_params(), w);
  md += config::fields_markdown_rows("command.", command_params(), w);
  md += config::fields_markdown_rows("tool.", tool_params(), w);
  md += config::fields_markdown_rows("planes[].", plane_params(), Plane{});
  md += config::fields_markdown_rows("robot.ik.", robot::ik_field_params(), robot::IkParams{});
  md += config::fields_markdown_rows("deformables[].body.", deformable::body_field_params(),
                                     deformable::DeformableParams{});
  md += config::fields_markdown_rows("deformables[].contact.", tip_contact_params(),
                                     collision::TipContactParams{});
  return md;
}

}  // namespace teleop::sim
