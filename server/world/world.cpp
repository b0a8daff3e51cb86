#include "server/world/world.hpp"

#include "common/util/clock.hpp"

#include <algorithm>
#include <cmath>

namespace teleop::sim {

namespace {

/// The slave's own state into the output (tip, planes' contact, joints).
void read_slave(const WorldData& d, WorldOutput& out) {
  if (d.robot) {
    const robot::RobotState& s = d.robot->state();
    out.tip_position_m = s.tip_pose.translation();
    out.tip_orientation = Eigen::Quaterniond(s.tip_pose.rotation());
    out.tip_velocity_mps = s.tip_twist.head<3>();
    out.tip_angular_velocity_radps = s.tip_twist.tail<3>();
    out.contact_force_n = s.tip_contact_force_n;
    out.contact_torque_nm = s.tip_contact_torque_nm;
    out.penetration_m = s.tip_penetration_m;
    out.in_contact = s.tip_in_contact;
    out.contact_object = s.tip_contact_plane;
    out.joint_count = s.n;
    for (int j = 0; j < s.n && j < kMaxJoints; ++j) {
      out.q_rad[static_cast<std::size_t>(j)] = s.q[j];
      out.qd_radps[static_cast<std::size_t>(j)] = s.qd[j];
      out.tau_nm[static_cast<std::size_t>(j)] = s.tau[j];
    }
    out.sim_time_s = s.sim_time_s;
  } else {
    const ToolState& t = d.tool;
    out.tip_position_m = t.position_m;
    out.tip_orientation = t.orientation;
    out.tip_velocity_mps = t.velocity_mps;
    out.tip_angular_velocity_radps = t.angular_velocity_radps;
    out.contact_force_n = t.contact_force_n;
    out.contact_torque_nm.setZero();
    out.penetration_m = t.penetration_m;
    out.contact_object = t.contact_object;
    out.in_contact = t.contact_object >= 0;
    out.joint_count = 0;
    out.sim_time_s = t.sim_time_s;
  }
}

/// Broad phase: true when the tip's swept sphere (plus a centimetre) reaches the body's box.
bool tip_may_reach(const Eigen::Matrix3Xd& x, const Eigen::Vector3d& from,
                   const Eigen::Vector3d& to, double tip_radius_m) {
  const Eigen::Vector3d lo = x.rowwise().minCoeff();
  const Eigen::Vector3d hi = x.rowwise().maxCoeff();
  const double margin = tip_radius_m + 0.01;
  const Eigen::Vector3d tlo = from.cwiseMin(to).array() - margin;
  const Eigen::Vector3d thi = from.cwiseMax(to).array() + margin;
  return (tlo.array() <= hi.array()).all() && (thi.array() >= lo.array()).all();
}

/// What the deformable bodies did to the tip in one step.
struct BodiesOnTip {
  double deepest_m = 0.0;
  int deepest_id = -1;
  double deformation_m = 0.0;
};

/// A body in contact: its force on the tip, the indentation since the touch, the deepest body.
void add_body_on_tip(const DeformableBodyData& b, const Eigen::Vector3d& tip_now,
                     BodiesOnTip& on_tip, int object_id, Eigen::Vector3d& force_on_tip_n) {
  if (!b.last.in_contact) return;
  force_on_tip_n += b.last.force_on_tip_n;
  on_tip.deformation_m =
      std::max(on_tip.deformation_m, (b.touch_centre_m - tip_now).dot(b.touch_normal));
  if (b.last.penetration_m > on_tip.deepest_m) {
    on_tip.deepest_m = b.last.penetration_m;
    on_tip.deepest_id = object_id;
  }
}

void push_touch_event(const DeformableBodyData& b, int object_id, double t_s, EventQueue& events) {
  events.push(
      b.last.in_contact ? EventKind::kContactBegin : EventKind::kContactEnd, Severity::kInfo, t_s,
      object_id,
      b.last.in_contact ? "tip touches the deformable body" : "tip leaves the deformable body");
}

/// Model fem: the contact result of the body's own step (its nodes kept out of the tip sphere):
/// force, normal (along the force), deepest node, nodes touched; the touch point when it began.
void read_fem_contact(DeformableBodyData& b, const Eigen::Vector3d& tip_now, double r,
                      deformable::StepStatus st) {
  const bool was = b.last.in_contact;
  collision::TipContactResult res;
  const deformable::DeformableState& s = b.state;
  const double fn = s.tip_force_n.norm();
  res.fault = st == deformable::StepStatus::kFaultReset;
  res.in_contact = !res.fault && s.tip_node_count > 0 && fn > 0.0;
  if (res.in_contact) {
    res.force_on_tip_n = s.tip_force_n;
    res.normal = s.tip_force_n / fn;
    res.normal_force_n = fn;
    res.penetration_m = s.tip_depth_m;
    res.max_node_depth_m = s.tip_depth_m;
    res.node_contacts = s.tip_node_count;
    res.contact_point_m = tip_now - r * res.normal;
    if (!was) {
      b.touch_centre_m = tip_now;
      b.touch_normal = res.normal;
    }
    res.entry_point_m = b.touch_centre_m - r * b.touch_normal;
  }
  res.began = res.in_contact && !was;
  res.ended = was && !res.in_contact;
  b.last = res;
}

/// Steps 1-2: tip against each body (contact, reaction, events), then each body.
BodiesOnTip step_bodies(const WorldModel& model, WorldData& d, double dt_s, EventQueue& events) {
  const Eigen::Vector3d tip_now = d.out.tip_position_m;
  const Eigen::Vector3d tip_vel = d.out.tip_velocity_mps;
  const double r = model.tip_radius_m();
  BodiesOnTip on_tip;
  d.deformable_force_n.setZero();
  d.cost.collision_us = d.cost.deformable_us = 0.0;
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    const DeformableBodyModel& bm = model.bodies[i];
    DeformableBodyData& b = d.bodies[i];
    b.state.f_ext.setZero();
    const bool was = b.last.in_contact;
    if (bm.body.params.model == deformable::ModelKind::kFem) {
      // the body keeps the tip sphere out of its surface within its own (sub-)steps
      const std::int64_t t1 = now_ns();
      const bool near = tip_may_reach(b.state.x, d.tip_prev_m, tip_now, r);
      b.state.tip_radius_m = near ? r : 0.0;
      b.state.tip_from_m = d.tip_prev_m;
      b.state.tip_to_m = tip_now;
      b.state.tip_velocity_mps = tip_vel;
      b.state.tip_friction_static = bm.contact.friction_static;
      b.state.tip_friction_kinetic = bm.contact.friction_kinetic;
      const deformable::StepStatus st = deformable::step(bm.body, b.state, dt_s, &events);
      d.cost.deformable_us += static_cast<double>(now_ns() - t1) * 1e-3;
      read_fem_contact(b, tip_now, r, st);
      add_body_on_tip(b, tip_now, on_tip, bm.object_id, d.deformable_force_n);
      if (b.last.in_contact != was) push_touch_event(b, bm.object_id, d.out.sim_time_s, events);
      continue;
    }
    // out of contact and clear of the body's box: the tree refit and the query are skipped
    // (about 20 us at level 4)
    const std::int64_t t0 = now_ns();
    const bool near = b.contact.in_contact() || tip_may_reach(b.state.x, d.tip_prev_m, tip_now, r);
    b.last = near ? b.contact.update(b.state.x, &b.state.v, d.tip_prev_m, tip_now, r, tip_vel, dt_s,
                                     b.state.f_ext)
                  : collision::TipContactResult{};
    d.cost.collision_us += static_cast<double>(now_ns() - t0) * 1e-3;
    if (b.last.fault) {
      events.push(EventKind::kFault, Severity::kWarning, d.out.sim_time_s, bm.object_id,
                  "tip-mesh contact saw non-finite data: contact dropped, force zero");
    }
    if (b.last.in_contact) {
      // the paper's x = |P(w) - P0|: how far the tip has gone in since it touched, along the
      // surface normal at the entry point
      b.touch_centre_m = b.last.entry_point_m + r * b.last.normal;
      b.touch_normal = b.last.normal;
      add_body_on_tip(b, tip_now, on_tip, bm.object_id, d.deformable_force_n);
      if (b.state.sleeping) deformable::wake(b.state);
    }
    if (b.last.in_contact != was) push_touch_event(b, bm.object_id, d.out.sim_time_s, events);
    const std::int64_t t1 = now_ns();
    const deformable::StepStatus st = deformable::step(bm.body, b.state, dt_s, &events);
    d.cost.deformable_us += static_cast<double>(now_ns() - t1) * 1e-3;
    if (st == deformable::StepStatus::kFaultReset) b.contact.release();
  }
  d.tip_prev_m = tip_now;
  return on_tip;
}

/// Step 3: the slave, with the deformable contact force on its tip.
void step_slave(const WorldModel& model, WorldData& d, const WorldCommand& cmd_in, double dt_s,
                EventQueue& events) {
  // a non-finite command never reaches either slave: it holds, and the fault is reported
  WorldCommand held;
  const bool finite = cmd_in.position_m.allFinite() && cmd_in.orientation.coeffs().allFinite() &&
                      cmd_in.velocity_mps.allFinite() &&
                      cmd_in.angular_velocity_radps.allFinite() &&
                      std::isfinite(cmd_in.kp_override_n_per_m);
  if (!finite) {
    held.hold = true;
    events.push(EventKind::kFault, Severity::kError, d.out.sim_time_s, 0.0,
                "world: non-finite command; the slave holds its pose");
  }
  const WorldCommand& cmd = finite ? cmd_in : held;
  if (d.robot) {
    robot::RobotInput in;
    in.mode = cmd.hold ? robot::ControlMode::kHold : robot::ControlMode::kTrackPose;
    in.target_position_m = cmd.position_m;
    in.target_orientation = (d.home_orientation * cmd.orientation).normalized();
    in.target_velocity_mps = cmd.velocity_mps;
    in.target_angular_velocity_radps = d.home_orientation * cmd.angular_velocity_radps;
    in.gain_scale = 1.0;
    in.external_force_n = d.deformable_force_n;
    d.robot->step(in, dt_s, &events);
  } else {
    tool_step_checked(model.tool, d.tool, tool_input(cmd, d.deformable_force_n), dt_s, events);
  }
}

/// A kinematic tool goes where it is told (before the contacts are resolved along its path);
/// a non-finite command leaves it where it is, at rest, with a fault event.
void move_kinematic_tool(WorldData& d, const WorldCommand& cmd, double dt_s, EventQueue& events) {
  ToolState& t = d.tool;
  const bool finite = cmd.position_m.allFinite() && cmd.velocity_mps.allFinite() &&
                      cmd.orientation.coeffs().allFinite();
  if (finite) {
    t.position_m = cmd.position_m;
    t.velocity_mps = cmd.velocity_mps;
    t.orientation = cmd.orientation.normalized();
  } else {
    t.velocity_mps.setZero();
    events.push(EventKind::kFault, Severity::kError, d.out.sim_time_s, 0.0,
                "world: non-finite kinematic command; the tool stays where it is");
  }
  t.angular_velocity_radps.setZero();
  t.contact_force_n.setZero();
  t.tracking_force_n.setZero();
  t.penetration_m = 0.0;
  t.contact_object = -1;
  t.sim_time_s += dt_s;
  read_slave(d, d.out);
}

// Contact events of the tip against the planes: from the plane it touched in the last step
// (`current`, -1 none) to `plane` now, a kContactEnd for the one it left and a kContactBegin for
// the one it touches (value: the plane id); `current` becomes `plane`.
void track_plane_contact(int& current, int plane, double sim_time_s, EventQueue& events) {
  if (plane == current) return;
  if (current >= 0) {
    events.push(EventKind::kContactEnd, Severity::kInfo, sim_time_s, current,
                "tip leaves the plane");
  }
  if (plane >= 0) {
    events.push(EventKind::kContactBegin, Severity::kInfo, sim_time_s, plane,
                "tip touches the plane");
  }
  current = plane;
}

}  // namespace

bool place_tool(const WorldModel& model, WorldData& d, const Eigen::Vector3d& position_m) {
  if (d.robot) return false;
  const double t = d.tool.sim_time_s;
  d.tool = tool_state_at(position_m);
  d.tool.sim_time_s = t;
  read_slave(d, d.out);
  d.tip_prev_m = position_m;
  d.deformable_force_n.setZero();
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    DeformableBodyData& b = d.bodies[i];
    b.contact.reset(b.state.x, model.bodies[i].body.mesh.triangles);
    b.last = collision::TipContactResult{};
  }
  return true;
}

namespace {

/// The indentation at which a fem body's contact stiffness is measured at load [m].
constexpr double kProbeDepthM = 0.005;

/// DeformableBodyModel::settle_s: steps of dt with the velocities relaxed, until the body is
/// still (every node slower than 0.1 mm/s) or settle_s has passed; then its clock starts at 0.
/// The planes are frictionless while it settles: the body comes to the shape it has when laid
/// down without shear in its contacts, an equilibrium with friction on too. (With friction, the
/// relaxed velocities leave the tangential forces of the sag stored in the contact patch, and
/// the released body rolls off them.)
void settle(const deformable::DeformableModel& m, deformable::DeformableState& s, double dt_s,
            double settle_s) {
  deformable::DeformableModel frictionless = m;
  frictionless.params.friction = false;
  const int steps = static_cast<int>(std::ceil(settle_s / dt_s));
  for (int k = 0; k < steps; ++k) {
    if (deformable::step(frictionless, s, dt_s, nullptr) == deformable::StepStatus::kFaultReset) {
      break;
    }
    s.v *= 0.97;
    s.centre_v *= 0.97;
    if (k > 10 && s.v.colwise().squaredNorm().maxCoeff() < 1e-8) break;
  }
  s.sim_time_s = 0.0;
}

}  // namespace

double probe_fem_stiffness(const deformable::DeformableModel& m,
                           const deformable::DeformableState& at, const Eigen::Vector3d& gravity,
                           double tip_radius_m, double dt_s, double depth_m) {
  deformable::DeformableState s = at;
  const Eigen::Vector3d up =
      gravity.norm() > 0.0 ? Eigen::Vector3d(-gravity.normalized()) : Eigen::Vector3d::UnitZ();
  Eigen::Index top = 0;
  (up.transpose() * s.x).maxCoeff(&top);
  const Eigen::Vector3d touch = s.x.col(top) + tip_radius_m * up;
  const double clearance = 0.002;
  const int ramp = static_cast<int>(std::ceil(0.3 / dt_s)), hold = ramp;
  Eigen::Vector3d tip = touch + clearance * up;
  s.tip_radius_m = tip_radius_m;
  s.tip_velocity_mps = -(clearance + depth_m) / (ramp * dt_s) * up;
  for (int k = 1; k <= ramp + hold; ++k) {
    const double a = std::min(1.0, static_cast<double>(k) / ramp);
    const Eigen::Vector3d next = touch + (clearance - a * (clearance + depth_m)) * up;
    if (k > ramp) s.tip_velocity_mps.setZero();
    s.tip_from_m = tip;
    s.tip_to_m = next;
    tip = next;
    if (deformable::step(m, s, dt_s, nullptr) == deformable::StepStatus::kFaultReset) return 0.0;
    if (k > ramp) s.v *= 0.97;
  }
  return s.tip_node_count > 0 ? s.tip_force_n.dot(up) / depth_m : 0.0;
}

WorldData make_world_data(const WorldModel& model) {
  WorldData d;
  if (model.has_robot()) {
    d.robot = std::make_unique<robot::RobotSim>(*model.robot, model.planes, model.robot_options);
    // commanded orientations are relative to the tip's home orientation: identity = home
    d.home_orientation = Eigen::Quaterniond(d.robot->state().tip_pose.rotation());
  } else {
    d.tool = tool_state_at(model.tool_start_m);
  }
  d.bodies.reserve(model.bodies.size());  // never grows again: contacts are not moved
  for (const DeformableBodyModel& bm : model.bodies) {
    DeformableBodyData& b = d.bodies.emplace_back();
    b.state = deformable::make_state(bm.body);
    if (bm.settle_s > 0.0) settle(bm.body, b.state, 1.0 / model.physics_rate_hz, bm.settle_s);
    b.contact_stiffness_n_per_m =
        bm.body.params.model == deformable::ModelKind::kFem
            ? probe_fem_stiffness(bm.body, b.state, model.gravity_mps2, model.tip_radius_m(),
                                  1.0 / model.physics_rate_hz, kProbeDepthM)
            : bm.contact.stiffness_n_per_m;
    b.contact.set_params(bm.contact);
    b.contact.set_node_areas(bm.body.area_m2);
    b.contact.reset(b.state.x, bm.body.mesh.triangles);
  }
  read_slave(d, d.out);
  d.tip_prev_m = d.out.tip_position_m;
  return d;
}

void world_step(const WorldModel& model, WorldData& d, const WorldCommand& cmd, double dt_s,
                EventQueue& events) {
  const bool kinematic = cmd.kinematic && !d.robot;
  if (kinematic) {
    // a prescribed probe moves first: its contacts are resolved along the path it was given
    const std::int64_t t0 = now_ns();
    move_kinematic_tool(d, cmd, dt_s, events);
    d.cost.slave_us = static_cast<double>(now_ns() - t0) * 1e-3;
  }
  // 1-2. tip against each deformable body, then the bodies
  const BodiesOnTip on_tip = step_bodies(model, d, dt_s, events);
  // 3. the slave
  if (!kinematic) {
    const std::int64_t t0 = now_ns();
    step_slave(model, d, cmd, dt_s, events);
    d.cost.slave_us = static_cast<double>(now_ns() - t0) * 1e-3;
  }
  // 4. outputs: the deformable contact adds to the planes' force on the tip
  WorldOutput& out = d.out;
  read_slave(d, out);
  track_plane_contact(d.plane_contact, out.in_contact ? out.contact_object : -1, out.sim_time_s,
                      events);
  out.contact_force_n += d.deformable_force_n;
  if (on_tip.deepest_m > out.penetration_m) {
    out.penetration_m = on_tip.deepest_m;
    out.contact_object = on_tip.deepest_id;
  }
  out.in_contact = out.in_contact || on_tip.deepest_id >= 0;
  out.deformation_m = on_tip.deformation_m;
  // the robot's joint-space PD has no Cartesian force to report: quasi-static estimate
  out.tracking_force_n =
      d.robot || kinematic ? Eigen::Vector3d(-out.contact_force_n) : d.tool.tracking_force_n;
}

}  // namespace teleop::sim
