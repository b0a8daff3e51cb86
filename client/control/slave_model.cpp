#include "client/control/slave_model.hpp"

#include "common/sim/plane.hpp"

#include <algorithm>
#include <cmath>

namespace teleop::master {

bool PointSlaveParams::add(const SlaveObstacle& o) {
  if (obstacle_count >= kMaxObstacles) return false;
  obstacles[static_cast<std::size_t>(obstacle_count++)] = o;
  return true;
}

passivity::SlavePortCommand port_command(const SlaveCommand& c) {
  passivity::SlavePortCommand p;
  p.scheme = static_cast<std::uint8_t>(c.scheme);
  p.session = c.passivity_session;
  p.enabled = c.enabled;
  p.position_m = c.position_m;
  p.velocity_mps = c.velocity_mps;
  p.wave_impedance_ns_per_m = c.wave_impedance_ns_per_m;
  p.wave_matched = c.wave_matched;
  p.wave_u_integral = c.wave_u_integral;
  p.wave_u_energy_j = c.wave_u_energy_j;
  p.tdpa_energy_in_j = c.tdpa_energy_in_j;
  return p;
}

void apply_port_report(const passivity::SlavePortReport& r, SlaveSample& s) {
  s.passivity_session = r.session;
  s.wave_v = r.wave_v;
  s.wave_v_integral = r.wave_v_integral;
  s.wave_v_energy_j = r.wave_v_energy_j;
  s.tdpa_energy_in_j = r.tdpa_energy_in_j;
  s.tdpa_energy_out_j = r.tdpa_energy_out_j;
  s.passivity_dissipated_j = r.dissipated_j;
}

void PointSlave::reset(const Eigen::Vector3d& position_m) {
  sample_ = SlaveSample{};
  sample_.position_m = position_m;
  sample_.valid = true;
  hold_m_ = position_m;
  holding_ = false;
  port_.reset();
  f_ctrl_.setZero();
}

void PointSlave::step(const SlaveCommand& cmd, double dt) {
  const PointSlaveParams& p = params_;
  SlaveSample& s = sample_;
  const double kp = cmd.position_gain_n_per_m > 0.0 ? cmd.position_gain_n_per_m : p.kp_n_per_m;
  // the passivity schemes' slave side (other schemes pass through unchanged)
  passivity::SlavePortState ps;
  ps.position_m = s.position_m;
  ps.velocity_mps = s.velocity_mps;
  ps.contact_force_n = s.contact_force_n;
  const passivity::SlavePortTarget pt =
      port_.before_step(port_command(cmd), ps, passivity::TrackingGains{kp, p.kd_ns_per_m}, dt);
  // hold the pose latched when the command is disabled (clutch open / no command yet)
  if (pt.hold && !holding_) hold_m_ = s.position_m;
  holding_ = pt.hold;
  const Eigen::Vector3d target = holding_ ? hold_m_ : pt.position_m;
  const Eigen::Vector3d target_v = holding_ ? Eigen::Vector3d::Zero() : pt.velocity_mps;

  // PD tracking with saturation
  Eigen::Vector3d f_ctrl =
      kp * (target - s.position_m) + p.kd_ns_per_m * (target_v - s.velocity_mps);
  const double fn = f_ctrl.norm();
  if (fn > p.max_force_n) f_ctrl *= p.max_force_n / fn;
  f_ctrl_ = f_ctrl;

  // penalty contact, compression only
  Eigen::Vector3d f_env = Eigen::Vector3d::Zero();
  double deepest = 0.0;
  int touched = -1;
  for (int i = 0; i < p.obstacle_count; ++i) {
    const SlaveObstacle& o = p.obstacles[static_cast<std::size_t>(i)];
    Eigen::Vector3d n;
    double depth = 0.0;
    if (o.kind == SlaveObstacle::Kind::kPlane) {
      n = o.normal;
      depth = p.radius_m - (o.normal.dot(s.position_m) - o.offset_m);
    } else {
      const Eigen::Vector3d d = s.position_m - o.centre_m;
      const double dist = d.norm();
      n = dist > 1e-12 ? Eigen::Vector3d(d / dist) : Eigen::Vector3d::UnitZ();
      depth = o.radius_m + p.radius_m - dist;
    }
    if (depth <= 0.0) continue;
    const double vn = n.dot(s.velocity_mps);
    // same law as the server's tool scene: damping ramps in over the first millimetre
    const double ramp = std::min(1.0, depth / teleop::sim::kPlaneDampingRampM);
    const double mag = std::max(0.0, o.stiffness_n_per_m * depth - ramp * o.damping_ns_per_m * vn);
    f_env += mag * n;
    if (depth > deepest) {
      deepest = depth;
      touched = o.id;
    }
  }

  const Eigen::Vector3d f = f_ctrl + f_env - p.linear_damping_ns_per_m * s.velocity_mps;
  s.velocity_mps += dt * f / p.mass_kg;
  s.position_m += dt * s.velocity_mps;
  s.orientation = holding_ ? s.orientation : cmd.orientation;
  s.contact_force_n = f_env;
  s.penetration_m = deepest;
  s.in_contact = touched >= 0;
  s.sim_time_s += dt;
  ++s.seq;
  s.command_seq = cmd.seq;
  s.command_send_time_s = cmd.send_time_s;
  s.valid = true;
  port_.after_step(f_ctrl, dt);
  apply_port_report(port_.report(), s);
}

}  // namespace teleop::master
