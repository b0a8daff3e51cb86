#include "client/viewer/hand_drive.hpp"

#include <algorithm>
#include <cmath>

namespace teleop::viewer {

bool HandDrive::intersect(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                          Eigen::Vector3d& hit) const {
  const double den = plane_normal_.dot(d);
  if (std::abs(den) < 1e-6) return false;  // the ray runs along the plane
  const double t = plane_normal_.dot(plane_point_ - o) / den;
  if (!(t > 0.0) || !std::isfinite(t)) return false;
  hit = o + t * d;
  return true;
}

Eigen::Vector3d HandDrive::clamp(const Eigen::Vector3d& x) const {
  const double h = p_.workspace_half_m;
  return x.cwiseMax(Eigen::Vector3d::Constant(-h)).cwiseMin(Eigen::Vector3d::Constant(h));
}

void HandDrive::grab(const Eigen::Vector3d& anchor, const Eigen::Vector3d& view_dir,
                     const Eigen::Vector3d& ray_origin, const Eigen::Vector3d& ray_dir) {
  plane_point_ = anchor;
  plane_normal_ = view_dir.normalized();
  dragging_ = intersect(ray_origin, ray_dir.normalized(), grab_hit_);
  grab_target_ = target_;
}

void HandDrive::drag(const Eigen::Vector3d& ray_origin, const Eigen::Vector3d& ray_dir) {
  if (!dragging_) return;
  Eigen::Vector3d hit;
  if (!intersect(ray_origin, ray_dir.normalized(), hit)) return;
  target_ = clamp(grab_target_ + (hit - grab_hit_) / p_.position_scale);
}

void HandDrive::nudge(const Eigen::Vector3d& direction, double dt_s) {
  if (direction.squaredNorm() == 0.0 || !(dt_s > 0.0)) return;
  target_ = clamp(target_ + direction.normalized() * p_.key_speed_mps * dt_s);
}

void HandDrive::set_target(const Eigen::Vector3d& device_m) {
  if (device_m.allFinite()) target_ = clamp(device_m);
}

void HandDrive::advance(double dt_s) {
  if (!(dt_s > 0.0)) return;
  // a trapezoid: accelerate at most max_accel toward the target, at most max_speed, and brake
  // so as to stop on it (v = sqrt(2 a d))
  const Eigen::Vector3d to_go = target_ - position_;
  const double dist = to_go.norm();
  const double a = p_.max_accel_mps2;
  if (dist < 1e-7 && velocity_.norm() < a * dt_s) {
    position_ = target_;
    velocity_.setZero();
    return;
  }
  // the braking speed of a discrete-time stop: covering `dist` in steps that each lose a dt of
  // speed ends on the target at about a dt
  const double h = a * dt_s * dt_s;
  const double brake = a * dt_s * (std::sqrt(0.25 + 2.0 * dist / h) - 0.5);
  Eigen::Vector3d want = Eigen::Vector3d::Zero();
  if (dist > 0.0) want = to_go * (std::min(p_.max_speed_mps, brake) / dist);
  Eigen::Vector3d dv = want - velocity_;
  const double dv_max = a * dt_s;
  if (dv.norm() > dv_max) dv *= dv_max / dv.norm();
  velocity_ += dv;
  Eigen::Vector3d move = velocity_ * dt_s;
  if (move.norm() >= dist && velocity_.dot(to_go) > 0.0) {  // arrives this step
    move = to_go;
    velocity_ = to_go / dt_s;
    if (velocity_.norm() > p_.max_speed_mps) velocity_ *= p_.max_speed_mps / velocity_.norm();
  }
  position_ += move;
}

}  // namespace teleop::viewer
