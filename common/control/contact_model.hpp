#pragma once
// Model-mediated teleoperation (docs/control.md, "Model-mediated"): a local model of what the
// slave's tip touches, estimated where the physics runs (the server's cycle, networked or
// in-process) and sent with every slave state; the master renders its force from its own
// position against the model, at its own rate, so the felt contact does not wait for the network.
//
// The model is a half-space in tip-centre coordinates of the slave frame (the frame master
// positions are mapped into): the tip centre x is inside by d = offset - n . x > 0, and the
// surface pushes it out with F = (k d + b max(0, -n . v)) n (never pulls). Before any contact it
// is the nearest surface of the geometry (a plane, or a sphere's tangent plane at the point
// nearest the tip) with the stiffness last estimated for it (or its nominal one); in contact, k,
// b and the offset come from the tip's own response, by recursive least squares on
//   f_n = k (offset - s) - b s_dot,     s = n . x,  f_n = n . f_contact,
// with exponential forgetting and a covariance bounded by its initial value (no wind-up while the
// tip rests). When the contact is on a surface the geometry knows (within 1 cm of it), s is
// measured from that surface along its normal where the tip is now, so sliding over a curved
// body keeps a true depth and the model's normal follows the curvature; otherwise along the
// force's first direction (a new contact starts when the force turns by more than 25 degrees).
//
// Allocation-free and deterministic; real-time safe.
#include <Eigen/Core>
#include <cstdint>

namespace teleop::mmt {

/// What the slave's tip touches or is about to touch. See the file comment.
struct LocalModel {
  bool valid = false;    ///< a surface is within range of the tip
  bool touched = false;  ///< stiffness and offset estimated from the contact itself
  std::int32_t object_id = -1;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< unit, out of the object
  double offset_m = 0.0;           ///< n . x of the tip centre where contact begins [m]
  double stiffness_n_per_m = 0.0;  ///< k [N/m]
  double damping_ns_per_m = 0.0;   ///< b, on compression only [N s/m]

  /// Depth of tip centre x inside the surface [m] (negative outside).
  double depth_m(const Eigen::Vector3d& x) const { return offset_m - normal.dot(x); }
  /// Force of the surface on a tip centre at x moving at v, slave frame [N] (zero if invalid).
  Eigen::Vector3d force_n(const Eigen::Vector3d& x, const Eigen::Vector3d& v) const;
  /// Elastic energy stored at x, k d^2 / 2 [J].
  double energy_j(const Eigen::Vector3d& x) const;
};

/// A surface of the geometry, as a half-space in tip-centre coordinates.
struct SurfacePrior {
  bool valid = false;
  std::int32_t object_id = -1;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double offset_m = 0.0;           ///< [m]
  double distance_m = 1e30;        ///< from the tip centre to the surface (negative inside) [m]
  double stiffness_n_per_m = 0.0;  ///< nominal k [N/m]
  double damping_ns_per_m = 0.0;   ///< nominal b [N s/m]
};

/// The plane n . p = plane_offset as seen by a tip of radius r: n . x = plane_offset + r.
SurfacePrior plane_prior(std::int32_t id, const Eigen::Vector3d& normal, double plane_offset_m,
                         double tip_radius_m, const Eigen::Vector3d& tip_m, double k, double b);
/// A sphere (centre, radius) as seen by a tip of radius r at tip_m: its tangent half-space at
/// the point nearest the tip.
SurfacePrior sphere_prior(std::int32_t id, const Eigen::Vector3d& centre_m, double radius_m,
                          double tip_radius_m, const Eigen::Vector3d& tip_m, double k, double b);
/// The nearer of two priors (`a` if `b` is not valid).
inline const SurfacePrior& nearer(const SurfacePrior& a, const SurfacePrior& b) {
  if (!b.valid) return a;
  if (!a.valid) return b;
  return b.distance_m < a.distance_m ? b : a;
}

/// Estimates the local model from the tip's motion and contact force. See the file comment.
class ContactEstimator {
 public:
  struct Params {
    double forgetting = 0.995;  ///< RLS forgetting per sample (0.995: ~0.2 s at 1 kHz)
    double min_force_n = 0.02;  ///< contact samples weaker than this are not used [N]
    double min_stiffness_n_per_m = 10.0;
    double max_stiffness_n_per_m = 1e5;
    double max_damping_ns_per_m = 200.0;
    double range_m = 0.1;  ///< a surface farther than this from the tip: no model
    double new_contact_angle_deg = 25.0;
    double geometric_gap_m = 0.01;  ///< a contact within this of a known surface is on it
  };

  ContactEstimator() = default;
  explicit ContactEstimator(const Params& p) : p_(p) {}
  /// Forgets everything (estimates and the last stiffness of each object).
  void reset();
  /// One physics step: tip centre x [m] and velocity v [m/s], environment force on the tip f
  /// [N], contact flag, and the nearest surface of the geometry (`prior`, may be invalid).
  void update(const Eigen::Vector3d& x, const Eigen::Vector3d& v, const Eigen::Vector3d& f,
              bool in_contact, const SurfacePrior& prior);
  const LocalModel& model() const { return model_; }
  /// Samples used in the current contact.
  std::uint64_t contact_samples() const { return samples_; }

 private:
  void start_contact(const Eigen::Vector3d& x, const Eigen::Vector3d& n, double f_n,
                     const SurfacePrior& prior);

  Params p_;
  LocalModel model_;
  bool in_contact_ = false;
  bool geometric_ = false;  // depth measured from the geometry's surface (see start_contact)
  std::uint64_t samples_ = 0;
  double s0_ = 0.0;  // n . x at the contact's start: the regressor is s - s0 (conditioning)
  Eigen::Vector3d theta_ = Eigen::Vector3d::Zero();  // f_n = t0 + t1 (s - s0) + t2 s_dot
  Eigen::Matrix3d cov_ = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d cov0_ = Eigen::Matrix3d::Identity();
  // the last estimate of the object touched last, used for its prior out of contact
  std::int32_t last_object_ = -1;
  double last_k_ = 0.0, last_b_ = 0.0;
};

}  // namespace teleop::mmt
