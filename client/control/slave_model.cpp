#include "client/control/slave_model.hpp"

#include "server/world/plane.hpp"

#include <algorithm>
#include <cmath>

namespace teleop::master {

bool PointSlaveParams::add(const SlaveObstacle& o) {
  if (obstacle_count >= kMaxObstacles) return false;
  obstacles[static_cast<std::size_t>(obstacle_count++)] = o;
  return true;
}

void PointSlave::reset(const Eigen::Vector3d& position_m) {
  sample_ = SlaveSample{};
  sample_.position_m = position_m;
  sample_.valid = true;
  hold_m_ = position_m;
  holding_ = false;
}

void PointSlave::step(const SlaveCommand& cmd, double dt) {
  const PointSlaveParams& p = params_;
  SlaveSample& s = sample_;
  // hold the pose latched when the command is disabled (clutch open / no command yet)
  if (!cmd.enabled && !holding_) hold_m_ = s.position_m;
  holding_ = !cmd.enabled;
  const Eigen::Vector3d target = holding_ ? hold_m_ : cmd.position_m;
  const Eigen::Vector3d target_v = holding_ ? Eigen::Vector3d::Zero() : cmd.velocity_mps;
  const double kp = cmd.position_gain_n_per_m > 0.0 ? cmd.position_gain_n_per_m : p.kp_n_per_m;

  // PD tracking with saturation
  Eigen::Vector3d f_ctrl =
      kp * (target - s.position_m) + p.kd_ns_per_m * (target_v - s.velocity_mps);
  const double fn = f_ctrl.norm();
  if (fn > p.max_force_n) f_ctrl *= p.max_force_n / fn;

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
}

}  // namespace teleop::master
