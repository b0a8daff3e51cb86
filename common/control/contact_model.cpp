#include "common/control/contact_model.hpp"

#include <algorithm>
#include <cmath>

namespace teleop::mmt {

Eigen::Vector3d LocalModel::force_n(const Eigen::Vector3d& x, const Eigen::Vector3d& v) const {
  if (!valid) return Eigen::Vector3d::Zero();
  const double d = depth_m(x);
  if (d <= 0.0) return Eigen::Vector3d::Zero();
  // a surface pushes, never pulls: the damping acts on compression only
  const double f = stiffness_n_per_m * d + damping_ns_per_m * std::max(0.0, -normal.dot(v));
  return std::max(0.0, f) * normal;
}

double LocalModel::energy_j(const Eigen::Vector3d& x) const {
  if (!valid) return 0.0;
  const double d = depth_m(x);
  return d > 0.0 ? 0.5 * stiffness_n_per_m * d * d : 0.0;
}

SurfacePrior plane_prior(std::int32_t id, const Eigen::Vector3d& normal, double plane_offset_m,
                         double tip_radius_m, const Eigen::Vector3d& tip_m, double k, double b) {
  SurfacePrior s;
  s.valid = true;
  s.object_id = id;
  s.normal = normal;
  s.offset_m = plane_offset_m + tip_radius_m;
  s.distance_m = normal.dot(tip_m) - s.offset_m;
  s.stiffness_n_per_m = k;
  s.damping_ns_per_m = b;
  return s;
}

SurfacePrior sphere_prior(std::int32_t id, const Eigen::Vector3d& centre_m, double radius_m,
                          double tip_radius_m, const Eigen::Vector3d& tip_m, double k, double b) {
  SurfacePrior s;
  const Eigen::Vector3d r = tip_m - centre_m;
  const double dist = r.norm();
  if (!(dist > 1e-9)) return s;  // the tip at the centre: no direction
  s.valid = true;
  s.object_id = id;
  s.normal = r / dist;
  s.offset_m = s.normal.dot(centre_m) + radius_m + tip_radius_m;
  s.distance_m = dist - radius_m - tip_radius_m;
  s.stiffness_n_per_m = k;
  s.damping_ns_per_m = b;
  return s;
}

void ContactEstimator::reset() {
  model_ = LocalModel{};
  in_contact_ = false;
  samples_ = 0;
  last_object_ = -1;
  last_k_ = last_b_ = 0.0;
}

void ContactEstimator::start_contact(const Eigen::Vector3d& x, const Eigen::Vector3d& n, double f_n,
                                     const SurfacePrior& prior) {
  in_contact_ = true;
  samples_ = 0;
  // touching a surface the geometry knows: depth is measured from it, along its normal at the
  // point nearest the tip, so a tip sliding over a curved body keeps a true depth; otherwise
  // along the force's first direction from where the contact began
  geometric_ = prior.valid && prior.distance_m < p_.geometric_gap_m;
  model_.normal = geometric_ ? prior.normal : n;
  s0_ = geometric_ ? prior.offset_m : n.dot(x);
  // start from what is known of the object: its last estimate, else its nominal stiffness
  const bool known = prior.valid && prior.object_id == last_object_ && last_k_ > 0.0;
  const double k = std::clamp(known         ? last_k_
                              : prior.valid ? prior.stiffness_n_per_m
                                            : 500.0,
                              p_.min_stiffness_n_per_m, p_.max_stiffness_n_per_m);
  const double b = std::clamp(known         ? last_b_
                              : prior.valid ? prior.damping_ns_per_m
                                            : 0.0,
                              0.0, p_.max_damping_ns_per_m);
  theta_ = Eigen::Vector3d(f_n, -k, -b);
  // one standard deviation: 1 N of force, the whole stiffness, 20 N s/m of damping
  cov0_ = Eigen::Vector3d(1.0, k * k, 400.0).asDiagonal();
  cov_ = cov0_;
  model_.object_id = prior.valid ? prior.object_id : -1;
}

void ContactEstimator::update(const Eigen::Vector3d& x, const Eigen::Vector3d& v,
                              const Eigen::Vector3d& f, bool in_contact,
                              const SurfacePrior& prior) {
  const double f_mag = f.norm();
  const bool touching = in_contact && f_mag >= p_.min_force_n && std::isfinite(f_mag);
  if (touching) {
    const Eigen::Vector3d n = f / f_mag;
    const double turn_cos = std::cos(p_.new_contact_angle_deg * M_PI / 180.0);
    const bool same_surface = geometric_ ? prior.valid && prior.object_id == model_.object_id
                                         : model_.normal.dot(n) >= turn_cos;
    if (!in_contact_ || !same_surface) start_contact(x, n, f_mag, prior);
    if (geometric_) {
      model_.normal = prior.normal;  // the surface's normal where the tip is now
      s0_ = prior.offset_m;
    }
    // recursive least squares with forgetting on f_n = t0 + t1 (s - s0) + t2 s_dot
    const Eigen::Vector3d& nn = model_.normal;
    const double f_n = nn.dot(f);
    const Eigen::Vector3d phi(1.0, nn.dot(x) - s0_, nn.dot(v));
    const Eigen::Vector3d pphi = cov_ * phi;
    const double denom = p_.forgetting + phi.dot(pphi);
    const Eigen::Vector3d gain = pphi / denom;
    theta_ += gain * (f_n - phi.dot(theta_));
    cov_ = (cov_ - gain * pphi.transpose()) / p_.forgetting;
    // bounded covariance: a resting tip (no excitation) must not wind it up
    for (int i = 0; i < 3; ++i) {
      if (cov_(i, i) > cov0_(i, i)) {
        const double s = std::sqrt(cov0_(i, i) / cov_(i, i));
        cov_.row(i) *= s;
        cov_.col(i) *= s;
      }
    }
    ++samples_;
    const double k = std::clamp(-theta_[1], p_.min_stiffness_n_per_m, p_.max_stiffness_n_per_m);
    model_.valid = true;
    model_.touched = true;
    model_.stiffness_n_per_m = k;
    model_.damping_ns_per_m = std::clamp(-theta_[2], 0.0, p_.max_damping_ns_per_m);
    model_.offset_m = s0_ + theta_[0] / k;
    last_object_ = model_.object_id;
    last_k_ = k;
    last_b_ = model_.damping_ns_per_m;
    return;
  }
  in_contact_ = false;
  model_.touched = false;
  if (!prior.valid || prior.distance_m > p_.range_m) {
    model_.valid = false;
    return;
  }
  // the geometry, with what was learnt of this object when it was last touched
  const bool known = prior.object_id == last_object_ && last_k_ > 0.0;
  model_.valid = true;
  model_.object_id = prior.object_id;
  model_.normal = prior.normal;
  model_.offset_m = prior.offset_m;
  model_.stiffness_n_per_m = known ? last_k_ : prior.stiffness_n_per_m;
  model_.damping_ns_per_m = known ? last_b_ : prior.damping_ns_per_m;
}

}  // namespace teleop::mmt
