#include "server/world/scene_world.hpp"

#include <cmath>

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

SceneWorld::SceneWorld(const SceneConfig& scene) : scene_(scene) {
  if (scene.kind == "robot") {
    const robot::RobotModel model = robot::load_robot_model(*scene.robot_node);
    robot_ = std::make_unique<robot::RobotSim>(model, scene.planes);
    tip_radius_m_ = model.tip_radius_m;
    // commanded orientations are relative to the tip's home orientation: identity = home
    home_orientation_ = Eigen::Quaterniond(robot_->state().tip_pose.rotation());
    tip_prev_ = robot_->state().tip_pose.translation();
  } else {
    tool_model_ = scene.tool;
    tool_state_.position_m = scene.tool_start_m;
    tool_state_.hold_position_m = scene.tool_start_m;
    tip_radius_m_ = tool_model_.radius_m;
    tip_prev_ = tool_state_.position_m;
  }
  out_.tracking_kp_n_per_m = scene.tool.kp_n_per_m;
  out_.tracking_kd_ns_per_m = scene.tool.kd_ns_per_m;
  int next_id = 10;
  for (const config::Node& n : scene.deformable_nodes) {
    n.reject_unknown_keys({"id", "body", "contact"});
    auto e = std::make_unique<DeformableEntry>();
    e->object_id = static_cast<int>(n.integer_or("id", next_id, 10, 99));
    next_id = e->object_id + 1;
    const deformable::DeformableParams params = deformable::load_deformable_params(n.at("body"));
    e->model = deformable::make_model(deformable::make_mesh_for(params), params, scene.planes);
    e->state = deformable::make_state(e->model);
    e->contact.set_params(load_tip_contact_params(n.child("contact")));
    e->contact.reset(e->state.x, e->model.mesh.triangles);
    bodies_.push_back(std::move(e));
  }
  read_outputs();
}

SceneWorld::~SceneWorld() = default;

DeformableView SceneWorld::deformable(int index) const {
  const DeformableEntry& e = *bodies_[static_cast<std::size_t>(index)];
  return {e.object_id, &e.model.mesh.triangles, &e.state.x};
}

void SceneWorld::step(const WorldCommand& cmd, double dt_s, EventQueue& events) {
  const Eigen::Vector3d tip_now = out_.tip_position_m;
  const Eigen::Vector3d tip_vel = out_.tip_velocity_mps;

  // 1-2. tip against each deformable body, then the bodies
  deformable_force_.setZero();
  double deepest = 0.0;
  int deepest_id = -1;
  double deformation = 0.0;
  for (auto& bp : bodies_) {
    DeformableEntry& b = *bp;
    b.state.f_ext.setZero();
    const bool was = b.last.in_contact;
    // broad phase: out of contact and the tip's swept sphere clear of the body's box (plus a
    // centimetre), the tree refit and the query are skipped (about 20 us at level 4)
    bool near = b.contact.in_contact();
    if (!near) {
      const Eigen::Vector3d lo = b.state.x.rowwise().minCoeff();
      const Eigen::Vector3d hi = b.state.x.rowwise().maxCoeff();
      const double margin = tip_radius_m_ + 0.01;
      const Eigen::Vector3d tlo = tip_prev_.cwiseMin(tip_now).array() - margin;
      const Eigen::Vector3d thi = tip_prev_.cwiseMax(tip_now).array() + margin;
      near = (tlo.array() <= hi.array()).all() && (thi.array() >= lo.array()).all();
    }
    if (near) {
      b.last = b.contact.update(b.state.x, &b.state.v, tip_prev_, tip_now, tip_radius_m_, tip_vel,
                                dt_s, b.state.f_ext);
    } else {
      b.last = collision::TipContactResult{};
    }
    if (b.last.fault) {
      events.push(EventKind::kFault, Severity::kWarning, out_.sim_time_s, b.object_id,
                  "tip-mesh contact saw non-finite data: contact dropped, force zero");
    }
    if (b.last.in_contact) {
      deformable_force_ += b.last.force_on_tip_n;
      // the paper's x = |P(w) - P0|: how far the tip has gone in since it touched, along the
      // surface normal at the entry point
      const Eigen::Vector3d touch_centre = b.last.entry_point_m + tip_radius_m_ * b.last.normal;
      deformation = std::max(deformation, (touch_centre - tip_now).dot(b.last.normal));
      if (b.last.penetration_m > deepest) {
        deepest = b.last.penetration_m;
        deepest_id = b.object_id;
      }
      if (b.state.sleeping) deformable::wake(b.state);
    }
    if (b.last.in_contact != was) {
      events.push(
          b.last.in_contact ? EventKind::kContactBegin : EventKind::kContactEnd, Severity::kInfo,
          out_.sim_time_s, b.object_id,
          b.last.in_contact ? "tip touches the deformable body" : "tip leaves the deformable body");
    }
    const deformable::StepStatus st = deformable::step(b.model, b.state, dt_s, &events);
    if (st == deformable::StepStatus::kFaultReset) b.contact.release();
  }
  tip_prev_ = tip_now;

  // 3. the slave, with the deformable contact force on its tip
  if (robot_) {
    robot::RobotInput in;
    in.mode = cmd.hold ? robot::ControlMode::kHold : robot::ControlMode::kTrackPose;
    in.target_position_m = cmd.position_m;
    in.target_orientation = (home_orientation_ * cmd.orientation).normalized();
    in.target_velocity_mps = cmd.velocity_mps;
    in.target_angular_velocity_radps = home_orientation_ * cmd.angular_velocity_radps;
    in.gain_scale = 1.0;
    in.external_force_n = deformable_force_;
    robot_->step(in, dt_s, &events);
  } else {
    ToolInput in = to_tool_input(cmd);
    in.external_force_n = deformable_force_;
    tool_step_checked(tool_model_, tool_state_, in, dt_s, events);
  }
  read_outputs();
  // 4. the deformable contact adds to the planes' force on the tip
  out_.contact_force_n += deformable_force_;
  if (deepest > out_.penetration_m) {
    out_.penetration_m = deepest;
    out_.contact_object = deepest_id;
  }
  out_.in_contact = out_.in_contact || deepest_id >= 0;
  out_.deformation_m = deformation;
  // the robot's joint-space PD has no Cartesian force to report: quasi-static estimate
  out_.tracking_force_n =
      robot_ ? Eigen::Vector3d(-out_.contact_force_n) : tool_state_.tracking_force_n;
  was_in_contact_ = out_.in_contact;
}

void SceneWorld::read_outputs() {
  if (robot_) {
    const robot::RobotState& s = robot_->state();
    out_.tip_position_m = s.tip_pose.translation();
    out_.tip_orientation = Eigen::Quaterniond(s.tip_pose.rotation());
    out_.tip_velocity_mps = s.tip_twist.head<3>();
    out_.tip_angular_velocity_radps = s.tip_twist.tail<3>();
    out_.contact_force_n = s.tip_contact_force_n;
    out_.contact_torque_nm = s.tip_contact_torque_nm;
    out_.penetration_m = s.tip_penetration_m;
    out_.in_contact = s.tip_in_contact;
    out_.contact_object = s.tip_contact_plane;
    out_.joint_count = s.n;
    for (int j = 0; j < s.n && j < kMaxJoints; ++j) {
      out_.q_rad[static_cast<std::size_t>(j)] = s.q[j];
      out_.qd_radps[static_cast<std::size_t>(j)] = s.qd[j];
      out_.tau_nm[static_cast<std::size_t>(j)] = s.tau[j];
    }
    out_.sim_time_s = s.sim_time_s;
  } else {
    out_.tip_position_m = tool_state_.position_m;
    out_.tip_orientation = tool_state_.orientation;
    out_.tip_velocity_mps = tool_state_.velocity_mps;
    out_.tip_angular_velocity_radps = tool_state_.angular_velocity_radps;
    out_.contact_force_n = tool_state_.contact_force_n;
    out_.contact_torque_nm.setZero();
    out_.penetration_m = tool_state_.penetration_m;
    out_.contact_object = tool_state_.contact_object;
    out_.in_contact = tool_state_.contact_object >= 0;
    out_.joint_count = 0;
    out_.sim_time_s = tool_state_.sim_time_s;
  }
}

}  // namespace teleop::sim
