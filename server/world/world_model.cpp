#include "server/world/world_model.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <numbers>
#include <sstream>
#include <vector>

#include "server/world/scene_params.hpp"

namespace teleop::sim {

collision::TipContactParams load_tip_contact_params(const config::Node& node) {
  collision::TipContactParams p;
  if (!node.defined()) return p;
  node.reject_unknown_keys(config::field_keys(tip_contact_params()));
  config::read_fields(node, tip_contact_params(), p);
  if (p.friction_kinetic > p.friction_static) {
    node.fail("friction_kinetic",
              "must not exceed friction_static (" + std::to_string(p.friction_static) + ")");
  }
  return p;
}

namespace {
/// Free space of a plane may be entered by at most this much at the start (a body resting on
/// the floor touches it; one that starts inside a wall explodes) [m].
constexpr double kStartPenetrationM = 1e-3;

std::string num(double v) {
  std::ostringstream os;
  os << std::setprecision(4) << v;
  return os.str();
}

std::string vec_text(const Eigen::Vector3d& v) {
  return "[" + num(v.x()) + ", " + num(v.y()) + ", " + num(v.z()) + "]";
}

std::string ms(double s) { return num(s * 1e3) + " ms"; }

std::string world_text(const WorldModel& s) {
  return "the world box " + vec_text(s.world_min_m) + " .. " + vec_text(s.world_max_m) +
         " m (world.min_m, world.max_m)";
}

std::filesystem::path relative_to(const std::string& file, const std::string& given) {
  std::filesystem::path p = given;
  if (p.is_relative()) p = std::filesystem::path(file).parent_path() / p;
  return p;
}

std::string body_name(const WorldModel& s, std::size_t i) {
  return "deformables[" + std::to_string(i) + "] (id " + std::to_string(s.bodies[i].object_id) +
         ")";
}

std::string body_shape(const deformable::DeformableModel& m) {
  return m.params.mesh_file.empty() ? "at level " + std::to_string(m.params.level)
                                    : "for mesh '" + m.params.mesh_file + "'";
}

/// A penalty contact the tool meets: its spring k and damper b and the scene fields naming them
/// (`field` + ".stiffness_n_per_m" / ".damping_ns_per_m"; a tool obstacle built in code has no
/// scene field and names itself).
struct ToolContact {
  double stiffness_n_per_m = 0.0;
  double damping_ns_per_m = 0.0;
  std::string field;
  bool scene_field = true;
};

/// Every contact of the tool slave: the planes, the deformable bodies' tip contacts and the
/// obstacles of a tool built in code. Each pushes with max(0, k d - b v_n): the damper acts on
/// both the approach and the separation velocity while the force is positive, and the step
/// applies the spring and the damper explicitly, so both enter the stable step with the PD's.
std::vector<ToolContact> tool_contacts(const WorldModel& s) {
  std::vector<ToolContact> out;
  for (std::size_t i = 0; i < s.planes.size(); ++i) {
    out.push_back({s.planes[i].stiffness_n_per_m, s.planes[i].damping_ns_per_m,
                   "planes[" + std::to_string(i) + "]"});
  }
  for (std::size_t i = 0; i < s.bodies.size(); ++i) {
    out.push_back({s.bodies[i].contact.stiffness_n_per_m, s.bodies[i].contact.damping_ns_per_m,
                   "deformables[" + std::to_string(i) + "].contact"});
  }
  for (int i = 0; i < s.tool.obstacle_count; ++i) {
    const Obstacle& o = s.tool.obstacles[static_cast<std::size_t>(i)];
    out.push_back(
        {o.stiffness_n_per_m, o.damping_ns_per_m, "tool obstacle " + std::to_string(i), false});
  }
  return out;
}

/// Largest stable step of the tool slave's law [s] (see physics_rate_problem); `why` says which
/// mode limits it.
double tool_limit_step_s(const WorldModel& s, std::string* why) {
  const ToolModel& t = s.tool;
  const double c = t.kd_ns_per_m + t.linear_damping_ns_per_m;
  double h = std::numeric_limits<double>::infinity();
  if (t.kp_n_per_m > 0.0) {
    const double w = std::sqrt(t.kp_n_per_m / t.mass_kg);
    const double zeta = c / (2.0 * std::sqrt(t.kp_n_per_m * t.mass_kg));
    h = 2.0 * (std::sqrt(1.0 + zeta * zeta) - zeta) / w;
    *why = "its PD (tool.kp_n_per_m " + num(t.kp_n_per_m) +
           ", damping tool.kd_ns_per_m + tool.linear_damping_ns_per_m " + num(c) +
           " N s/m, tool.mass_kg " + num(t.mass_kg) + ": w " + num(w) + " rad/s, zeta " +
           num(zeta) + ") is stable for h w <= 2 (sqrt(1 + zeta^2) - zeta)";
  } else if (c > 0.0) {
    h = 2.0 * t.mass_kg / c;
    *why = "its damping (tool.kd_ns_per_m + tool.linear_damping_ns_per_m " + num(c) +
           " N s/m on tool.mass_kg " + num(t.mass_kg) + ") is stable for h c / m <= 2";
  }
  if (t.kp_rot_nm_per_rad > 0.0 || t.kd_rot_nms_per_rad > 0.0) {
    // the rotational PD on the tool's inertia, the same law
    const double inertia = t.inertia_kgm2();
    const double kr = t.kp_rot_nm_per_rad, cr = t.kd_rot_nms_per_rad;
    const double wr = std::sqrt(kr / inertia);
    const double zr = kr > 0.0 ? cr / (2.0 * std::sqrt(kr * inertia)) : 0.0;
    const double hr = kr > 0.0 ? 2.0 * (std::sqrt(1.0 + zr * zr) - zr) / wr : 2.0 * inertia / cr;
    if (hr < h) {
      h = hr;
      *why = "its rotational PD (tool.kp_rot_nm_per_rad " + num(kr) + ", tool.kd_rot_nms_per_rad " +
             num(cr) + " on the inertia 0.4 m r^2 = " + num(inertia) +
             " kg m^2 of tool.mass_kg and tool.radius_m: w " + num(wr) + " rad/s, zeta " + num(zr) +
             ") is stable for h w <= 2 (sqrt(1 + zeta^2) - zeta)";
    }
  }
  // in contact: the PD plus each contact's spring and damper (see ToolContact)
  for (const ToolContact& k : tool_contacts(s)) {
    const double stiffness = t.kp_n_per_m + k.stiffness_n_per_m;
    const double damping = c + k.damping_ns_per_m;
    const double hc =
        (std::sqrt(damping * damping + 4.0 * stiffness * t.mass_kg) - damping) / stiffness;
    if (hc < h) {
      h = hc;
      const std::string k_name = k.scene_field ? k.field + ".stiffness_n_per_m" : k.field + " k";
      const std::string c_name = k.scene_field ? k.field + ".damping_ns_per_m" : k.field + " c";
      *why = "in contact, its PD (tool.kp_n_per_m " + num(t.kp_n_per_m) + " N/m) plus " + k_name +
             " " + num(k.stiffness_n_per_m) + " N/m and " + c_name + " " + num(k.damping_ns_per_m) +
             " N s/m, both applied explicitly, is stable for h^2 (kp + "
             "k_contact) / m + 2 h (c + c_contact) / m <= 4 (tool.mass_kg " +
             num(t.mass_kg) + ", c = tool.kd_ns_per_m + tool.linear_damping_ns_per_m " + num(c) +
             " N s/m)";
    }
  }
  return h;
}

/// The tip's node penalty on body `b` (surface models; the fem body keeps the tip out within its
/// own sub-steps): each node inside the tip sphere gets a spring k_i = k w_i and a damper
/// c_i = c w_i (w_i = A_i / node_reference_area_m2) from the contact pass, once per physics step,
/// held over the body's sub-steps. On node mass m_i that is an explicit step of h: stable for
/// h w_i <= 2 (w_i^2 = k_i / m_i) and h c_i / m_i <= 2. Returns the shortest step both allow [s]
/// (infinity without a node penalty); `why` names the node, its mass and the limiting term.
double node_penalty_step_s(const DeformableBodyModel& b, std::string* why, bool* spring = nullptr) {
  const collision::TipContactParams& c = b.contact;
  const deformable::DeformableModel& m = b.body;
  double h = std::numeric_limits<double>::infinity();
  if (m.params.model == deformable::ModelKind::kFem || !(c.node_stiffness_n_per_m > 0.0)) return h;
  for (int i = 0; i < m.node_count; ++i) {
    const double w = c.node_reference_area_m2 > 0.0 && i < m.area_m2.size()
                         ? m.area_m2(i) / c.node_reference_area_m2
                         : 1.0;
    const double mass = m.mass_kg(i);
    const double k = c.node_stiffness_n_per_m * w, d = c.node_damping_ns_per_m * w;
    if (!(mass > 0.0)) continue;
    const double hk = k > 0.0 ? 2.0 / std::sqrt(k / mass) : h;
    const double hd = d > 0.0 ? 2.0 * mass / d : h;
    if (std::min(hk, hd) < h) {
      h = std::min(hk, hd);
      if (spring) *spring = hk <= hd;
      *why =
          "node " + std::to_string(i) + " (mass " + num(mass) + " kg, area " +
          num(w * c.node_reference_area_m2) + " m^2) gets " +
          (hk <= hd ? "the spring contact.node_stiffness_n_per_m " + num(c.node_stiffness_n_per_m) +
                          " x " + num(w) + " = " + num(k) + " N/m, stable for h sqrt(k / m) <= 2"
                    : "the damper contact.node_damping_ns_per_m " + num(c.node_damping_ns_per_m) +
                          " x " + num(w) + " = " + num(d) + " N s/m, stable for h c / m <= 2");
    }
  }
  return h;
}

/// The tip's proxy spring on body `b` (surface models): its reaction k x + c x' goes to the body's
/// nodes once per physics step, held over the sub-steps, (1 - patch_blend) to the anchor
/// triangle's corners (barycentric, a third each at its centroid) and patch_blend spread over
/// the nodes within patch_radius_m (n_p of them, n_p = pi r_p^2 / mean node area); the
/// indentation x moves with a corner by its barycentric weight (a third). So a node carries at
/// most k s and c s, s = ((1 - blend) / 3 + blend / n_p) / 3, and on the lightest node mass m the
/// step is stable for h sqrt(k s / m) <= 2 and h c s / m <= 2. Returns the shortest step both
/// allow [s] (infinity for a fem body, which keeps the tip out in its own sub-steps).
double proxy_reaction_step_s(const DeformableBodyModel& b, std::string* why, bool* spring) {
  const collision::TipContactParams& c = b.contact;
  const deformable::DeformableModel& m = b.body;
  double h = std::numeric_limits<double>::infinity();
  if (m.params.model == deformable::ModelKind::kFem || m.node_count == 0) return h;
  const double mean_area = m.area_m2.sum() / m.node_count;
  const double patch_nodes = std::max(
      1.0, std::numbers::pi * c.patch_radius_m * c.patch_radius_m / std::max(mean_area, 1e-300));
  const double share = ((1.0 - c.patch_blend) / 3.0 + c.patch_blend / patch_nodes) / 3.0;
  const double mass = m.mass_kg.minCoeff();
  const double k = c.stiffness_n_per_m * share, d = c.damping_ns_per_m * share;
  const double hk = k > 0.0 ? 2.0 / std::sqrt(k / mass) : h;
  const double hd = d > 0.0 ? 2.0 * mass / d : h;
  h = std::min(hk, hd);
  *spring = hk <= hd;
  *why = "the reaction of the tip's proxy spring reaches a node (the lightest, " + num(mass) +
         " kg) with the share s = ((1 - patch_blend " + num(c.patch_blend) + ") / 3 + " +
         num(c.patch_blend) + " / " + num(patch_nodes) + " nodes within patch_radius_m " +
         num(c.patch_radius_m) + ") / 3 = " + num(share) +
         (*spring ? " of contact.stiffness_n_per_m " + num(c.stiffness_n_per_m) +
                        " N/m, stable for h sqrt(k s / m) <= 2"
                  : " of contact.damping_ns_per_m " + num(c.damping_ns_per_m) +
                        " N s/m, stable for h c s / m <= 2");
  return h;
}

/// Why the tip's contact on body i is unstable at step dt ("" when it is not): the node penalty
/// (node_penalty_step_s) and the proxy's reaction (proxy_reaction_step_s).
std::string tip_contact_problem(const WorldModel& s, std::size_t i, double dt) {
  std::string why;
  bool spring = true;
  const double hn = node_penalty_step_s(s.bodies[i], &why, &spring);
  std::string why_p;
  bool spring_p = true;
  const double hp = proxy_reaction_step_s(s.bodies[i], &why_p, &spring_p);
  const bool proxy = hp < hn;
  const double h = std::min(hn, hp);
  if (!(dt > kRateSafety * h)) return "";
  const collision::TipContactParams& c = s.bodies[i].contact;
  const double r = kRateSafety * h / dt;  // an allowed stiffness scales as r^2, a damping as r
  const bool k_limits = proxy ? spring_p : spring;
  const std::string field = "deformables[" + std::to_string(i) + "].contact." +
                            (proxy ? "" : "node_") +
                            (k_limits ? "stiffness_n_per_m" : "damping_ns_per_m");
  const double value = proxy ? (k_limits ? c.stiffness_n_per_m : c.damping_ns_per_m)
                             : (k_limits ? c.node_stiffness_n_per_m : c.node_damping_ns_per_m);
  return body_name(s, i) + "'s contact with the tip: " + (proxy ? why_p : why) +
         " at the physics step h (the contact force is applied once per step and held over the "
         "body's sub-steps, so sub-steps do not help): h <= " +
         ms(kRateSafety * h) + " with the safety factor " + num(kRateSafety) + ": lower " + field +
         " to at most " + num(k_limits ? value * r * r : value * r) + " at this rate, or ";
}

/// Largest kp / kd of a robot joint [1/s]: its motor row tracks the velocity qd_ref + (kp / kd)
/// (q_ref - q), which corrects the position error as e <- (1 - h kp / kd) e per step.
double joint_correction_rate_per_s(const robot::RobotModel& r, int* which) {
  double rate = 0.0;
  for (int i = 0; i < r.n; ++i) {
    const robot::LinkModel& l = r.links[i];
    const double k = l.kd_nms_per_rad > 0.0 ? l.kp_nm_per_rad / l.kd_nms_per_rad : 0.0;
    if (k > rate) {
      rate = k;
      *which = i;
    }
  }
  return rate;
}

std::string joint_drive_problem(const robot::RobotModel& r, double dt) {
  int i = 0;
  const double k = joint_correction_rate_per_s(r, &i);
  if (!(dt * k > 2.0 * kRateSafety)) return "";
  const robot::LinkModel& l = r.links[i];
  return "the robot's joint " + std::to_string(i + 1) + " (robot.links[" + std::to_string(i) +
         "].joint): its drive tracks the velocity qd_ref + (kp / kd) (q_ref - q), which corrects "
         "the error as e <- (1 - h kp / kd) e and diverges for h kp / kd > 2 (kp_nm_per_rad " +
         num(l.kp_nm_per_rad) + ", kd_nms_per_rad " + num(l.kd_nms_per_rad) +
         ": h kp / kd = " + num(dt * k) + ", allowed " + num(2.0 * kRateSafety) +
         "): lower kp_nm_per_rad or raise kd_nms_per_rad";
}
}  // namespace

double min_physics_rate_hz(const WorldModel& s) {
  double rate = 0.0;
  if (s.has_robot()) {
    int joint = 0;
    rate = std::max(
        rate, std::max(s.robot->ik.gain_per_s, joint_correction_rate_per_s(*s.robot, &joint)) /
                  (2.0 * kRateSafety));
  } else {
    std::string why;
    const double h = tool_limit_step_s(s, &why);
    if (std::isfinite(h)) rate = std::max(rate, 1.0 / (kRateSafety * h));
  }
  for (const auto& b : s.bodies) {
    const double h = b.body.stable_step_s;
    if (std::isfinite(h) && h > 0.0) {
      rate = std::max(rate, 1.0 / (h * static_cast<double>(b.body.params.max_substeps)));
    }
    std::string why;
    bool spring = true;
    const double hn =
        std::min(node_penalty_step_s(b, &why), proxy_reaction_step_s(b, &why, &spring));
    if (std::isfinite(hn) && hn > 0.0) rate = std::max(rate, 1.0 / (kRateSafety * hn));
  }
  return rate;
}

double max_position_gain_n_per_m(const WorldModel& s, double rate_hz) {
  if (s.has_robot() || !(rate_hz > 0.0) || !std::isfinite(rate_hz)) return kMaxPositionGainNPerM;
  const ToolModel& t = s.tool;
  const double h = 1.0 / (rate_hz * kRateSafety);
  const double c = t.kd_ns_per_m + t.linear_damping_ns_per_m;
  // free: h^2 kp / m + 2 h c / m <= 4; in each contact (k_c, c_c):
  // h^2 (kp + k_c) / m + 2 h (c + c_c) / m <= 4
  double kp = (4.0 * t.mass_kg - 2.0 * h * c) / (h * h);
  for (const ToolContact& k : tool_contacts(s)) {
    kp = std::min(
        kp, (4.0 * t.mass_kg - 2.0 * h * (c + k.damping_ns_per_m)) / (h * h) - k.stiffness_n_per_m);
  }
  return std::clamp(kp, 0.0, kMaxPositionGainNPerM);
}

std::string physics_rate_problem(const WorldModel& s, double rate_hz) {
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz)) return "is not a positive rate";
  const double dt = 1.0 / rate_hz;
  const std::string at_least =
      "raise the rate to at least " + num(std::ceil(min_physics_rate_hz(s))) + " Hz";
  const std::string asks = "(dt " + ms(dt) + ") is too coarse for ";
  if (s.has_robot()) {
    const double g = s.robot->ik.gain_per_s;
    if (dt * g > 2.0 * kRateSafety) {
      return asks + "the robot: its resolved-rate IK (robot.ik.gain_per_s " + num(g) +
             " 1/s) integrates the task error as e <- (1 - h g) e, which diverges for h g > 2 "
             "(here h g = " +
             num(dt * g) + ", allowed " + num(2.0 * kRateSafety) + "): " + at_least +
             " or lower robot.ik.gain_per_s";
    }
    const std::string joint = joint_drive_problem(*s.robot, dt);
    if (!joint.empty()) return asks + joint + ": " + at_least;
  } else {
    std::string why;
    const double h = tool_limit_step_s(s, &why);
    if (dt > kRateSafety * h) {
      return asks + "the tool slave (semi-implicit Euler): " + why +
             ", i.e. dt <= " + ms(kRateSafety * h) + " with the safety factor " + num(kRateSafety) +
             ": " + at_least + ", or lower the stiffness, or raise tool.mass_kg";
    }
  }
  for (std::size_t i = 0; i < s.bodies.size(); ++i) {
    const std::string contact = tip_contact_problem(s, i, dt);
    if (!contact.empty()) return asks + contact + at_least;
  }
  for (std::size_t i = 0; i < s.bodies.size(); ++i) {
    const deformable::DeformableModel& m = s.bodies[i].body;
    const int need = m.substeps_needed(dt);
    if (need > m.params.max_substeps) {
      return asks + body_name(s, i) + ": its largest stable step is " + ms(m.stable_step_s) + " " +
             body_shape(m) + " (" + deformable::to_string(m.params.integrator) + ", w_max " +
             num(m.omega_max_rad_per_s) + " rad/s, zeta " + num(m.damping_ratio_top) +
             "), the scene asks " + ms(dt) + ": that needs " + std::to_string(need) +
             " sub-steps, more than its max_substeps " + std::to_string(m.params.max_substeps) +
             " (the stable step comes from the body's stiffness, body.youngs_modulus_pa, " +
             "edge_stiffness_n_per_m, radial_stiffness_n_per_m3, its node-plane contact, " +
             "body.contact_frequency_rad_per_s " + num(m.params.contact_frequency_rad_per_s) +
             " rad/s, and its damping rates, body.stiffness_damping_s, radial_damping_s, " +
             "mass_damping_per_s): lower dt (" + at_least + "), lower the stiffness or the " +
             "damping, use implicit_euler or raise max_substeps";
    }
  }
  return "";
}

std::vector<std::string> physics_rate_notes(const WorldModel& s, double rate_hz) {
  std::vector<std::string> notes;
  if (!(rate_hz > 0.0)) return notes;
  const double dt = 1.0 / rate_hz;
  for (std::size_t i = 0; i < s.bodies.size(); ++i) {
    const deformable::DeformableModel& m = s.bodies[i].body;
    const int n = m.substeps_for(dt);
    if (n <= 1) continue;
    notes.push_back(body_name(s, i) + ": dt " + ms(dt) + " > largest stable step " +
                    ms(m.stable_step_s) + " " + body_shape(m) + " (" +
                    deformable::to_string(m.params.integrator) + ", w_max " +
                    num(m.omega_max_rad_per_s) + " rad/s): " + std::to_string(n) +
                    " sub-steps of " + ms(dt / n) + " per physics step");
  }
  return notes;
}

// parse_world_model, section by section (each fills its part of `s` and checks it against what
// the earlier sections set: the world box first, then physics, command, tool, planes, robot,
// deformables, and last the checks that need all of them).
namespace {

void check_scene_root(const config::Node& root) {
  if (root.empty_document()) {
    throw config::ConfigError(root.file() +
                              ": the scene is empty (an empty file, /dev/null or only comments): "
                              "a scene is a YAML mapping with at least 'kind' (tool or robot); "
                              "see deploy/scenes/default.yaml");
  }
  if (!root.is_map()) {
    throw config::ConfigError(root.file() + ": field '<root>': value '" +
                              (root.raw().IsScalar() ? root.raw().Scalar() : "a list") +
                              "' is not a scene: a scene is a YAML mapping of fields such as "
                              "'kind', 'physics', 'planes'");
  }
}

void parse_world_box(const config::Node& root, WorldModel& s) {
  if (root.has("world")) {
    const auto w = root.at("world");
    w.reject_unknown_keys(config::field_keys(world_box_params()));
    config::read_fields(w, world_box_params(), s);
    for (int i = 0; i < 3; ++i) {
      if (s.world_min_m[i] >= s.world_max_m[i]) {
        w.fail("min_m", "value " + vec_text(s.world_min_m) + ": element " + std::to_string(i) +
                            " must be below world.max_m's (" + num(s.world_max_m[i]) + ")");
      }
    }
  }
}

void parse_physics(const config::Node& root, WorldModel& s) {
  if (root.has("physics")) {
    const auto p = root.at("physics");
    p.reject_unknown_keys(config::field_keys(physics_params()));
    config::read_fields(p, physics_params(), s);
  }
}

void parse_command(const config::Node& root, WorldModel& s) {
  if (root.has("command")) {
    const auto c = root.at("command");
    c.reject_unknown_keys(config::field_keys(command_params()));
    config::read_fields(c, command_params(), s);
    for (int i = 0; i < 3; ++i) {
      if (s.workspace_min_m[i] >= s.workspace_max_m[i]) {
        c.fail("workspace_min_m", "element " + std::to_string(i) + " must be below " +
                                      "workspace_max_m's (" + std::to_string(s.workspace_max_m[i]) +
                                      ")");
      }
    }
  }
  for (int i = 0; i < 3; ++i) {
    if (s.workspace_min_m[i] < s.world_min_m[i]) {
      root.fail("command.workspace_min_m",
                "value " + vec_text(s.workspace_min_m) + " reaches outside " + world_text(s));
    }
    if (s.workspace_max_m[i] > s.world_max_m[i]) {
      root.fail("command.workspace_max_m",
                "value " + vec_text(s.workspace_max_m) + " reaches outside " + world_text(s));
    }
  }
}

void parse_tool(const config::Node& root, WorldModel& s) {
  s.tool.gravity_mps2 = s.gravity_mps2;
  if (root.has("tool")) {
    const auto t = root.at("tool");
    t.reject_unknown_keys(config::field_keys(tool_params()));
    config::read_fields(t, tool_params(), s);
  }
}

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
      if (!p.is_map()) p.fail("", "must be a mapping with at least 'normal'");
      p.reject_unknown_keys(config::field_keys(plane_params(), {"name", "normal"}));
      Plane pl;
      pl.id = static_cast<int>(100 + i);
      pl.name = p.string_or("name", "plane" + std::to_string(i));
      for (std::size_t j = 0; j < s.planes.size(); ++j) {
        if (s.planes[j].name == pl.name) {
          p.fail("name", "value '" + pl.name + "' is already the name of planes[" +
                             std::to_string(j) + "]; plane names must be unique");
        }
      }
      const auto n = p.numbers("normal", 3, -1e3, 1e3);
      pl.normal = Eigen::Vector3d(n[0], n[1], n[2]);
      if (pl.normal.norm() < 1e-6) p.fail("normal", "must not be the zero vector");
      pl.normal.normalize();
      config::read_fields(p, plane_params(), pl);
      s.planes.push_back(pl);
    }
  }
  for (const Plane& pl : s.planes) s.tool.add(Obstacle::of(pl));
}

void parse_robot(const config::Node& root, WorldModel& s) {
  if (root.has("robot")) {
    // `robot: {include: FILE}` takes the `robot` mapping of another file (relative paths are
    // relative to this scene file), so one robot description serves several scenes. The robot
    // is validated in every scene that has one; only a robot scene drives it.
    const config::Node r = root.at("robot");
    std::optional<robot::RobotModel> rm;
    if (r.is_map() && r.has("include")) {
      r.reject_unknown_keys({"include"});
      const std::string given = r.string("include");
      const std::string inc = relative_to(root.file(), given).string();
      std::error_code ec;
      if (!std::filesystem::is_regular_file(inc, ec)) {
        r.fail("include", "value '" + given + "': '" + inc + "' " +
                              (std::filesystem::is_directory(inc, ec) ? "is a directory"
                               : std::filesystem::exists(inc, ec)     ? "is not a regular file"
                                                                      : "does not exist") +
                              "; relative paths are relative to the scene file");
      }
      try {
        const config::Node inc_root = config::Node::load_file(inc);
        if (inc_root.empty_document()) {
          throw config::ConfigError(inc + ": the file is empty; it must hold a 'robot' mapping");
        }
        rm = robot::load_robot_model(inc_root.at("robot"));
      } catch (const config::ConfigError& e) {
        r.fail("include", "value '" + given + "': " + e.what());
      }
    } else {
      rm = robot::load_robot_model(r);
    }
    if (s.slave == SlaveKind::kRobot) s.robot = std::move(rm);
  }
  if (s.slave == SlaveKind::kRobot && !s.robot) {
    root.fail("robot", "is required when kind is 'robot'");
  }
  if (s.has_robot()) {
    const Eigen::Vector3d base = s.robot->base.translation();
    if ((base.array() < s.world_min_m.array()).any() ||
        (base.array() > s.world_max_m.array()).any()) {
      root.fail("robot", "base position " + vec_text(base) +
                             " (robot.base.position_m) is outside " + world_text(s));
    }
  }
}

/// deformables[i]: its id (unique, 10..99; `next_id` is the automatic one) and its body, built
/// automatically or from the explicit fields. `mesh_given` is the mesh_file as written.
DeformableBodyModel parse_deformable_body(const config::Node& n, const WorldModel& s, int& next_id,
                                          std::string& mesh_given) {
  n.reject_unknown_keys({"id", "body", "contact", "settle_s"});
  DeformableBodyModel b;
  b.settle_s = n.number_or("settle_s", 0.0, 0.0, 10.0);
  b.object_id = static_cast<int>(n.integer_or("id", next_id, 10, 99));
  if (b.object_id > 99) {
    n.fail("id", "value '" + std::to_string(b.object_id) +
                     "' (assigned automatically: the previous id + 1) is out of the allowed "
                     "range [10, 99]; give the ids explicitly");
  }
  for (std::size_t j = 0; j < s.bodies.size(); ++j) {
    if (s.bodies[j].object_id == b.object_id) {
      n.fail("id", "value '" + std::to_string(b.object_id) + "'" +
                       (n.has("id") ? "" : " (assigned automatically: the previous id + 1)") +
                       " is already the id of deformables[" + std::to_string(j) +
                       "]; ids must be unique");
    }
  }
  next_id = b.object_id + 1;
  const config::Node body = n.at("body");
  if (deformable::has_auto_field(body)) {
    // `auto` fields pick the model from the measured table (server/deformable/model_select)
    deformable::AutoBody ab =
        deformable::load_deformable_body(body, 1.0 / s.physics_rate_hz, s.planes);
    b.body = std::move(ab.model);
    b.auto_summary = ab.summary();
    b.auto_report = ab.report();
  } else {
    for (const char* key : {"tolerance_pct", "tolerance_mm", "budget_us", "model_table"}) {
      if (body.has(key)) {
        body.fail(key,
                  "is used only when model, integrator, level or kernel is auto (automatic "
                  "model selection); remove it or set one of them to auto");
      }
    }
    deformable::DeformableParams explicit_params = deformable::load_deformable_params(body);
    mesh_given = explicit_params.mesh_file;
    if (!mesh_given.empty()) {
      explicit_params.mesh_file = relative_to(s.file, mesh_given).string();
    }
    try {
      if (!explicit_params.tet_mesh_file.empty()) {
        explicit_params.tet_mesh_file = relative_to(s.file, explicit_params.tet_mesh_file).string();
      }
      b.body = deformable::make_model(explicit_params, s.planes);
    } catch (const mesh::MeshError& e) {
      if (mesh_given.empty()) body.fail("", e.what());
      body.fail("mesh_file", "value '" + mesh_given + "': " + e.what());
    } catch (const config::ConfigError& e) {
      body.fail("", e.what());
    }
  }
  return b;
}

/// The body is runnable (a stable step exists) and starts inside the world box and in the free
/// space of every plane.
void check_deformable_placement(const config::Node& body, const DeformableBodyModel& b,
                                const WorldModel& s, const std::string& mesh_given) {
  const deformable::DeformableParams& params = b.body.params;
  if (!(b.body.stable_step_s > 0.0)) {
    body.fail("integrator",
              "value 'explicit_euler' without stiffness damping (stiffness_damping_s " +
                  num(params.stiffness_damping_s) + ", radial_damping_s " +
                  num(params.radial_damping_s) +
                  ") is unstable at any step: give both dampings > 0, or use "
                  "symplectic_euler or implicit_euler");
  }
  // the body must start inside the world box and in the free space of every plane
  const Eigen::Matrix3Xd& x = b.body.mesh.vertices;
  const Eigen::Vector3d lo = x.rowwise().minCoeff();
  const Eigen::Vector3d hi = x.rowwise().maxCoeff();
  const Eigen::Vector3d size = hi - lo;
  const std::string size_field = mesh_given.empty() ? "radius_m" : "mesh_scale";
  const std::string size_value = mesh_given.empty() ? num(params.radius_m) : num(params.mesh_scale);
  if ((size.array() > (s.world_max_m - s.world_min_m).array()).any()) {
    body.fail(size_field, "value '" + size_value + "': the body is " + num(size.x()) + " x " +
                              num(size.y()) + " x " + num(size.z()) + " m and does not fit in " +
                              world_text(s));
  }
  const std::string centre_value = "value '" + vec_text(params.centre_m) + "'";
  if ((lo.array() < s.world_min_m.array()).any() || (hi.array() > s.world_max_m.array()).any()) {
    body.fail("centre_m", centre_value + ": the body spans " + vec_text(lo) + " .. " +
                              vec_text(hi) + " m, outside " + world_text(s) +
                              ": move centre_m or widen the world box");
  }
  for (std::size_t j = 0; j < s.planes.size(); ++j) {
    const Plane& pl = s.planes[j];
    const double d = (pl.normal.transpose() * x).minCoeff() - pl.offset_m;
    if (d < -kStartPenetrationM) {
      body.fail("centre_m", centre_value + ": the body (" + size_field + " " + size_value +
                                ") starts " + num(-d) + " m behind plane '" + pl.name +
                                "' (planes[" + std::to_string(j) +
                                "]); every node must start in free space (at most " +
                                num(kStartPenetrationM * 1e3) +
                                " mm inside a plane): move centre_m or shrink the body");
    }
  }
}

void parse_deformables(const config::Node& root, WorldModel& s) {
  if (!root.has("deformables")) return;
  const auto ds = root.at("deformables");
  if (!ds.is_sequence()) ds.fail("", "must be a list of deformable bodies");
  int next_id = 10;
  for (std::size_t i = 0; i < ds.size(); ++i) {
    const config::Node n = ds.at(i);
    if (!n.is_map()) n.fail("", "must be a mapping with at least 'body'");
    std::string mesh_given;
    DeformableBodyModel b = parse_deformable_body(n, s, next_id, mesh_given);
    check_deformable_placement(n.at("body"), b, s, mesh_given);
    const config::Node contact = n.child("contact");
    b.contact = load_tip_contact_params(contact);
    const config::Node model_field = n.at("body").child("model");
    if (model_field.defined() && model_field.raw().IsScalar() &&
        model_field.raw().Scalar() == "fem" && contact.defined()) {
      // a body of model fem keeps the tip out with its own surface pressure: only friction
      // applies (with model auto the other fields serve the surface model it may choose)
      for (const auto& kv : contact.raw()) {
        const std::string key = kv.first.Scalar();
        if (key != "friction_static" && key != "friction_kinetic") {
          contact.fail(key,
                       "does not apply to a body of model fem, which keeps the tip out "
                       "with its surface's pressure (body.contact_pressure_stiffness_pa_per_m)"
                       "; allowed here: friction_static, friction_kinetic");
        }
      }
    }
    s.bodies.push_back(std::move(b));
  }
}

void check_tool_start(const config::Node& root, const WorldModel& s) {
  for (int i = 0; i < 3; ++i) {
    if (s.tool_start_m[i] < s.workspace_min_m[i] || s.tool_start_m[i] > s.workspace_max_m[i]) {
      root.fail("tool.start_position_m", "must lie inside the command workspace");
    }
  }
  if (!s.has_robot()) {
    for (std::size_t j = 0; j < s.planes.size(); ++j) {
      const Plane& pl = s.planes[j];
      const double d = pl.normal.dot(s.tool_start_m) - pl.offset_m - s.tool.radius_m;
      if (d < -kStartPenetrationM) {
        root.fail("tool.start_position_m", "value " + vec_text(s.tool_start_m) +
                                               ": the tool (radius " + num(s.tool.radius_m) +
                                               " m) starts " + num(-d) + " m behind plane '" +
                                               pl.name + "' (planes[" + std::to_string(j) +
                                               "]); it must start in free space");
      }
    }
  }
}

}  // namespace

WorldModel parse_world_model(const config::Node& root) {
  check_scene_root(root);
  WorldModel s;
  s.file = root.file();
  root.reject_unknown_keys(
      {"name", "kind", "world", "physics", "command", "tool", "planes", "robot", "deformables"});
  s.name = root.string_or("name", s.name);
  const std::string kind = root.choice_or("kind", "tool", {"tool", "robot"});
  s.slave = kind == "robot" ? SlaveKind::kRobot : SlaveKind::kTool;
  parse_world_box(root, s);
  const bool rate_given = root.has("physics") && root.at("physics").has("rate_hz");
  parse_physics(root, s);
  parse_command(root, s);
  parse_tool(root, s);
  parse_planes(root, s);
  parse_robot(root, s);
  parse_deformables(root, s);
  check_tool_start(root, s);
  const std::string problem = physics_rate_problem(s, s.physics_rate_hz);
  if (!problem.empty()) {
    root.fail("physics.rate_hz", "value '" + num(s.physics_rate_hz) + "'" +
                                     (rate_given ? "" : " (the default)") + " " + problem);
  }
  return s;
}

WorldModel load_world_model(const std::string& file) {
  return parse_world_model(config::Node::load_file(file));
}

WorldModel tool_world_model(const ToolModel& tool, const Eigen::Vector3d& start_m, double rate_hz) {
  WorldModel m;
  m.name = "tool (in code)";
  m.slave = SlaveKind::kTool;
  m.physics_rate_hz = rate_hz;
  m.gravity_mps2 = tool.gravity_mps2;
  m.tool = tool;
  m.tool_start_m = start_m;
  for (int i = 0; i < tool.obstacle_count; ++i) {
    const Obstacle& o = tool.obstacles[static_cast<std::size_t>(i)];
    if (o.kind != Obstacle::Kind::kPlane) continue;
    Plane p;
    p.id = o.id;
    p.name = "plane " + std::to_string(o.id);
    p.normal = o.normal;
    p.offset_m = o.offset_m;
    p.stiffness_n_per_m = o.stiffness_n_per_m;
    p.damping_ns_per_m = o.damping_ns_per_m;
    m.planes.push_back(p);
  }
  return m;
}

}  // namespace teleop::sim
