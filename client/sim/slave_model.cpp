#include "client/sim/slave_model.hpp"

namespace teleop::master {

void PointSlave::reset(const Eigen::Vector3d& position_m) {
  state_ = sim::tool_state_at(position_m);
  sample_ = SlaveSample{};
  sample_.position_m = position_m;
  sample_.valid = true;
  port_.reset();
  estimator_.reset();
}

mmt::SurfacePrior PointSlave::nearest_surface(const Eigen::Vector3d& tip_m) const {
  mmt::SurfacePrior best;
  for (int i = 0; i < params_.obstacle_count; ++i) {
    const sim::Obstacle& o = params_.obstacles[static_cast<std::size_t>(i)];
    best =
        mmt::nearer(best, o.kind == sim::Obstacle::Kind::kPlane
                              ? mmt::plane_prior(o.id, o.normal, o.offset_m, params_.radius_m,
                                                 tip_m, o.stiffness_n_per_m, o.damping_ns_per_m)
                              : mmt::sphere_prior(o.id, o.centre_m, o.radius_m, params_.radius_m,
                                                  tip_m, o.stiffness_n_per_m, o.damping_ns_per_m));
  }
  return best;
}

void PointSlave::step(const SlaveCommand& cmd, double dt) {
  const double kp =
      cmd.position_gain_n_per_m > 0.0 ? cmd.position_gain_n_per_m : params_.kp_n_per_m;
  // the passivity schemes' slave side (other schemes pass through unchanged)
  const passivity::SlavePortTarget pt = port_.before_step(
      passivity::port_command(cmd),
      passivity::SlavePortState{state_.position_m, state_.velocity_mps, state_.contact_force_n},
      passivity::TrackingGains{kp, params_.kd_ns_per_m}, dt);
  sim::ToolInput in;
  in.target_position_m = pt.position_m;
  in.target_orientation = cmd.orientation;
  in.target_velocity_mps = pt.velocity_mps;
  in.kp_override_n_per_m = cmd.position_gain_n_per_m;
  in.hold = pt.hold;
  sim::tool_step(params_, state_, in, dt);
  port_.after_step(state_.tracking_force_n, dt);

  SlaveSample& s = sample_;
  s.position_m = state_.position_m;
  s.orientation = state_.orientation;
  s.velocity_mps = state_.velocity_mps;
  s.contact_force_n = state_.contact_force_n;
  s.penetration_m = state_.penetration_m;
  s.in_contact = state_.contact_object >= 0;
  s.sim_time_s = state_.sim_time_s;
  ++s.seq;
  s.command_seq = cmd.seq;
  s.command_send_time_s = cmd.send_time_s;
  s.valid = true;
  passivity::apply_port_report(port_.report(), s);
  estimator_.update(s.position_m, s.velocity_mps, s.contact_force_n, s.in_contact,
                    nearest_surface(s.position_m));
  s.model = estimator_.model();
}

}  // namespace teleop::master
