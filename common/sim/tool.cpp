#include "common/sim/tool.hpp"

#include <algorithm>
#include <cmath>

namespace teleop::sim {

void tool_step(const ToolModel& model, ToolState& state, const ToolInput& input, double dt) {
  // hold: latch the pose once and track it with zero velocity
  if (input.hold && !state.was_holding) state.hold_position_m = state.position_m;
  state.was_holding = input.hold;
  const Eigen::Vector3d target_p = input.hold ? state.hold_position_m : input.target_position_m;
  const Eigen::Vector3d target_v = input.hold ? Eigen::Vector3d::Zero() : input.target_velocity_mps;
  const double kp = input.kp_override_n_per_m > 0.0 ? input.kp_override_n_per_m : model.kp_n_per_m;

  // translational PD with saturation, plus gravity compensation
  Eigen::Vector3d f_ctrl =
      kp * (target_p - state.position_m) + model.kd_ns_per_m * (target_v - state.velocity_mps);
  const double fn = f_ctrl.norm();
  if (fn > model.max_force_n) f_ctrl *= model.max_force_n / fn;
  state.tracking_force_n = f_ctrl;
  if (model.gravity_compensation) f_ctrl -= model.mass_kg * model.gravity_mps2;
  state.control_force_n = f_ctrl;

  // penalty contact with each obstacle, compression only, in the order they were added
  Eigen::Vector3d f_contact = Eigen::Vector3d::Zero();
  state.penetration_m = 0.0;
  state.contact_object = -1;
  for (int i = 0; i < model.obstacle_count; ++i) {
    const Obstacle& o = model.obstacles[static_cast<std::size_t>(i)];
    Eigen::Vector3d n;
    double depth = 0.0;
    if (o.kind == Obstacle::Kind::kPlane) {
      n = o.normal;
      depth = model.radius_m - (o.normal.dot(state.position_m) - o.offset_m);
    } else {
      const Eigen::Vector3d d = state.position_m - o.centre_m;
      const double dist = d.norm();
      n = dist > 1e-12 ? Eigen::Vector3d(d / dist) : Eigen::Vector3d::UnitZ();
      depth = o.radius_m + model.radius_m - dist;
    }
    if (depth <= 0.0) continue;
    const double vn = n.dot(state.velocity_mps);
    // damping ramps in over the first millimetre so the force is continuous at contact onset
    const double ramp = std::min(1.0, depth / kPlaneDampingRampM);
    const double mag = std::max(0.0, o.stiffness_n_per_m * depth - ramp * o.damping_ns_per_m * vn);
    f_contact += mag * n;
    if (depth > state.penetration_m) {
      state.penetration_m = depth;
      state.contact_object = o.id;
    }
  }
  state.contact_force_n = f_contact;

  const Eigen::Vector3d f_total = f_ctrl + f_contact + input.external_force_n +
                                  model.mass_kg * model.gravity_mps2 -
                                  model.linear_damping_ns_per_m * state.velocity_mps;
  state.velocity_mps += dt * f_total / model.mass_kg;
  state.position_m += dt * state.velocity_mps;

  // rotational PD on the quaternion error (shortest arc), semi-implicit
  const Eigen::Quaterniond target_q =
      input.hold ? state.orientation : input.target_orientation.normalized();
  Eigen::Quaterniond err = target_q * state.orientation.conjugate();
  if (err.w() < 0.0) err.coeffs() *= -1.0;
  const Eigen::AngleAxisd aa(err);
  const Eigen::Vector3d rot_err = aa.angle() * aa.axis();
  const Eigen::Vector3d w_target =
      input.hold ? Eigen::Vector3d::Zero() : input.target_angular_velocity_radps;
  const Eigen::Vector3d torque =
      model.kp_rot_nm_per_rad * rot_err +
      model.kd_rot_nms_per_rad * (w_target - state.angular_velocity_radps);
  state.angular_velocity_radps += dt * torque / model.inertia_kgm2();
  const Eigen::Vector3d dtheta = dt * state.angular_velocity_radps;
  const double angle = dtheta.norm();
  if (angle > 1e-12) {
    state.orientation =
        (Eigen::Quaterniond(Eigen::AngleAxisd(angle, dtheta / angle)) * state.orientation)
            .normalized();
  }
  state.sim_time_s += dt;
}

ToolState tool_state_at(const Eigen::Vector3d& position_m) {
  ToolState s;
  s.position_m = position_m;
  s.hold_position_m = position_m;
  return s;
}

bool tool_step_checked(const ToolModel& model, ToolState& state, const ToolInput& input, double dt,
                       EventQueue& events) {
  const ToolState before = state;
  tool_step(model, state, input, dt);
  if (state.position_m.allFinite() && state.velocity_mps.allFinite() &&
      state.orientation.coeffs().allFinite() && state.angular_velocity_radps.allFinite()) {
    return true;
  }
  state = before;
  state.velocity_mps.setZero();
  state.angular_velocity_radps.setZero();
  state.contact_force_n.setZero();
  events.push(EventKind::kFault, Severity::kError, state.sim_time_s, 0.0,
              "tool step produced a non-finite state; restored the previous state");
  return false;
}

double tool_kinetic_energy(const ToolModel& model, const ToolState& state) {
  return 0.5 * model.mass_kg * state.velocity_mps.squaredNorm() +
         0.5 * model.inertia_kgm2() * state.angular_velocity_radps.squaredNorm();
}

}  // namespace teleop::sim
