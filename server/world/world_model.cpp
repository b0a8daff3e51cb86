#include "server/world/world_model.hpp"

#include <filesystem>

namespace teleop::sim {

collision::TipContactParams load_tip_contact_params(const config::Node& node) {
  collision::TipContactParams p;
  if (!node.defined()) return p;
  node.reject_unknown_keys({"stiffness_n_per_m", "damping_ns_per_m", "damping_ramp_m",
                            "friction_static", "friction_kinetic", "max_force_n", "patch_radius_m",
                            "patch_blend", "node_stiffness_n_per_m", "node_damping_ns_per_m"});
  p.stiffness_n_per_m = node.number_or("stiffness_n_per_m", p.stiffness_n_per_m, 1.0, 1e7);
  p.damping_ns_per_m = node.number_or("damping_ns_per_m", p.damping_ns_per_m, 0.0, 1e5);
  p.damping_ramp_m = node.number_or("damping_ramp_m", p.damping_ramp_m, 0.0, 0.1);
  p.friction_static = node.number_or("friction_static", p.friction_static, 0.0, 5.0);
  p.friction_kinetic = node.number_or("friction_kinetic", p.friction_kinetic, 0.0, 5.0);
  if (p.friction_kinetic > p.friction_static) {
    node.fail("friction_kinetic",
              "must not exceed friction_static (" + std::to_string(p.friction_static) + ")");
  }
  p.max_force_n = node.number_or("max_force_n", p.max_force_n, 0.0, 1e5);
  p.patch_radius_m = node.number_or("patch_radius_m", p.patch_radius_m, 0.0, 1.0);
  p.patch_blend = node.number_or("patch_blend", p.patch_blend, 0.0, 1.0);
  p.node_stiffness_n_per_m =
      node.number_or("node_stiffness_n_per_m", p.node_stiffness_n_per_m, 0.0, 1e6);
  p.node_damping_ns_per_m =
      node.number_or("node_damping_ns_per_m", p.node_damping_ns_per_m, 0.0, 1e4);
  return p;
}

namespace {
Eigen::Vector3d vec3(const config::Node& n, const std::string& key, const Eigen::Vector3d& def,
                     double lo, double hi) {
  const auto v = n.numbers_or(key, {def.x(), def.y(), def.z()}, lo, hi);
  return {v[0], v[1], v[2]};
}

// `physics` and `command`: rates, gravity, command timeout and workspace.
void parse_physics_and_command(const config::Node& root, WorldModel& s) {
  if (root.has("physics")) {
    const auto p = root.at("physics");
    p.reject_unknown_keys({"rate_hz", "visual_rate_hz", "gravity_mps2"});
    s.physics_rate_hz = p.number_or("rate_hz", s.physics_rate_hz, 10.0, 20000.0);
    s.visual_rate_hz = p.number_or("visual_rate_hz", s.visual_rate_hz, 1.0, 240.0);
    s.gravity_mps2 = vec3(p, "gravity_mps2", s.gravity_mps2, -100.0, 100.0);
  }
  if (root.has("command")) {
    const auto c = root.at("command");
    c.reject_unknown_keys({"timeout_s", "workspace_min_m", "workspace_max_m"});
    s.command_timeout_s = c.number_or("timeout_s", s.command_timeout_s, 0.001, 10.0);
    s.workspace_min_m = vec3(c, "workspace_min_m", s.workspace_min_m, -100.0, 100.0);
    s.workspace_max_m = vec3(c, "workspace_max_m", s.workspace_max_m, -100.0, 100.0);
    for (int i = 0; i < 3; ++i) {
      if (s.workspace_min_m[i] >= s.workspace_max_m[i]) {
        c.fail("workspace_min_m", "element " + std::to_string(i) + " must be below " +
                                      "workspace_max_m's (" + std::to_string(s.workspace_max_m[i]) +
                                      ")");
      }
    }
  }
}

// `tool`: the free tool's mass, size, gains and start position.
void parse_tool(const config::Node& root, WorldModel& s) {
  if (root.has("tool")) {
    const auto t = root.at("tool");
    t.reject_unknown_keys({"mass_kg", "radius_m", "kp_n_per_m", "kd_ns_per_m", "kp_rot_nm_per_rad",
                           "kd_rot_nms_per_rad", "linear_damping_ns_per_m", "max_force_n",
                           "gravity_compensation", "start_position_m"});
    s.tool.mass_kg = t.number_or("mass_kg", s.tool.mass_kg, 1e-3, 100.0);
    s.tool.radius_m = t.number_or("radius_m", s.tool.radius_m, 1e-3, 1.0);
    s.tool.kp_n_per_m = t.number_or("kp_n_per_m", s.tool.kp_n_per_m, 0.0, 1e6);
    s.tool.kd_ns_per_m = t.number_or("kd_ns_per_m", s.tool.kd_ns_per_m, 0.0, 1e4);
    s.tool.kp_rot_nm_per_rad = t.number_or("kp_rot_nm_per_rad", s.tool.kp_rot_nm_per_rad, 0, 1e4);
    s.tool.kd_rot_nms_per_rad =
        t.number_or("kd_rot_nms_per_rad", s.tool.kd_rot_nms_per_rad, 0, 1e3);
    s.tool.linear_damping_ns_per_m =
        t.number_or("linear_damping_ns_per_m", s.tool.linear_damping_ns_per_m, 0.0, 1e4);
    s.tool.max_force_n = t.number_or("max_force_n", s.tool.max_force_n, 0.1, 1e5);
    s.tool.gravity_compensation = t.boolean_or("gravity_compensation", true);
    s.tool_start_m = vec3(t, "start_position_m", s.tool_start_m, -100.0, 100.0);
  }
}

// `planes`: at most kMaxPlanes, ids 100, 101, ... in order, unit normals.
void parse_planes(const config::Node& root, WorldModel& s) {
  if (root.has("planes")) {
    const auto ps = root.at("planes");
    if (!ps.is_sequence()) ps.fail("", "must be a list of planes");
    if (ps.size() > static_cast<std::size_t>(kMaxPlanes)) {
      root.fail("planes", "has " + std::to_string(ps.size()) + " entries; at most " +
                              std::to_string(kMaxPlanes) + " are allowed");
    }
    for (std::size_t i = 0; i < ps.size(); ++i) {
      const auto p = ps.at(i);
      p.reject_unknown_keys(
          {"name", "normal", "offset_m", "stiffness_n_per_m", "damping_ns_per_m", "friction"});
      Plane pl;
      pl.id = static_cast<int>(100 + i);
      pl.name = p.string_or("name", "plane" + std::to_string(i));
      const auto n = p.numbers("normal", 3, -1e3, 1e3);
      pl.normal = Eigen::Vector3d(n[0], n[1], n[2]);
      if (pl.normal.norm() < 1e-6) p.fail("normal", "must not be the zero vector");
      pl.normal.normalize();
      pl.offset_m = p.number_or("offset_m", 0.0, -100.0, 100.0);
      pl.stiffness_n_per_m = p.number_or("stiffness_n_per_m", pl.stiffness_n_per_m, 1.0, 1e8);
      pl.damping_ns_per_m = p.number_or("damping_ns_per_m", pl.damping_ns_per_m, 0.0, 1e6);
      pl.friction = p.number_or("friction", pl.friction, 0.0, 5.0);
      s.planes.push_back(pl);
    }
  }
}

// The `robot` mapping, if any: inline or `{include: FILE}`.
std::optional<config::Node> robot_node_of(const config::Node& root) {
  std::optional<config::Node> robot_node;
  if (root.has("robot")) {
    // `robot: {include: FILE}` takes the `robot` mapping of another file (relative paths are
    // relative to this scene file), so one robot description serves several scenes
    const config::Node r = root.at("robot");
    if (r.is_map() && r.has("include")) {
      r.reject_unknown_keys({"include"});
      std::filesystem::path inc = r.string("include");
      if (inc.is_relative()) inc = std::filesystem::path(root.file()).parent_path() / inc;
      robot_node = config::Node::load_file(inc.string()).at("robot");
    } else {
      robot_node = r;
    }
  }
  return robot_node;
}

// `deformables`: each body's id (10..99, by default the previous one's + 1), its model built
// against the scene's planes, and its tip contact parameters.
void parse_deformables(const config::Node& root, WorldModel& s) {
  if (root.has("deformables")) {
    const auto ds = root.at("deformables");
    if (!ds.is_sequence()) ds.fail("", "must be a list of deformable bodies");
    int next_id = 10;
    for (std::size_t i = 0; i < ds.size(); ++i) {
      const config::Node n = ds.at(i);
      n.reject_unknown_keys({"id", "body", "contact"});
      DeformableBodyModel b;
      b.object_id = static_cast<int>(n.integer_or("id", next_id, 10, 99));
      next_id = b.object_id + 1;
      const deformable::DeformableParams params = deformable::load_deformable_params(n.at("body"));
      b.body = deformable::make_model(deformable::make_mesh_for(params), params, s.planes);
      b.contact = load_tip_contact_params(n.child("contact"));
      s.bodies.push_back(std::move(b));
    }
  }
}
}  // namespace

WorldModel parse_world_model(const config::Node& root) {
  WorldModel s;
  s.file = root.file();
  root.reject_unknown_keys(
      {"name", "kind", "physics", "command", "tool", "planes", "robot", "deformables"});
  s.name = root.string_or("name", s.name);
  const std::string kind = root.choice_or("kind", "tool", {"tool", "robot"});
  s.slave = kind == "robot" ? SlaveKind::kRobot : SlaveKind::kTool;

  parse_physics_and_command(root, s);
  s.tool.gravity_mps2 = s.gravity_mps2;
  parse_tool(root, s);
  parse_planes(root, s);
  for (const Plane& pl : s.planes) s.tool.add(Obstacle::of(pl));

  const std::optional<config::Node> robot_node = robot_node_of(root);
  if (s.slave == SlaveKind::kRobot && !robot_node) {
    root.fail("robot", "is required when kind is 'robot'");
  }
  if (s.slave == SlaveKind::kRobot) s.robot = robot::load_robot_model(*robot_node);
  parse_deformables(root, s);
  for (int i = 0; i < 3; ++i) {
    if (s.tool_start_m[i] < s.workspace_min_m[i] || s.tool_start_m[i] > s.workspace_max_m[i]) {
      root.fail("tool.start_position_m", "must lie inside the command workspace");
    }
  }
  return s;
}

WorldModel load_world_model(const std::string& file) {
  return parse_world_model(config::Node::load_file(file));
}

}  // namespace teleop::sim
