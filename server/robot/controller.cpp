#include "server/robot/controller.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>

namespace teleop::sim::robot {

namespace {

using TaskMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;
using TaskVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 6, 1>;

// Variable damping^2 [m^2] of the least-squares solve from s.sigma_min_m: zero away from
// singularities, up to damping_max^2 at sigma = 0. Sets s.damping_m and s.near_singular and
// reports entering a singular neighbourhood.
double singular_damping2(const IkParams& ik, ControllerState& s, double sim_time_s,
                         EventQueue* ev) {
  const double eps = ik.singular_threshold_m;
  double lambda2 = 0.0;
  if (s.sigma_min_m < eps) {
    const double ratio = s.sigma_min_m / eps;
    lambda2 = ik.damping_max_m * ik.damping_max_m * (1.0 - ratio * ratio);
  }
  s.damping_m = std::sqrt(lambda2);
  const bool singular = s.sigma_min_m < eps;
  if (singular && !s.near_singular) {
    ++s.singular_events;
    if (ev) {
      char msg[96];
      std::snprintf(msg, sizeof(msg), "robot near a singular pose: sigma_min %.4f m",
                    s.sigma_min_m);
      ev->push(EventKind::kLimit, Severity::kWarning, sim_time_s, s.sigma_min_m, msg);
    }
  }
  s.near_singular = singular;

  return lambda2;
}

// kTrackPose: the reference joint velocity qd [rad/s] (size n) towards the target pose by
// damped least squares on the weighted task Jacobian at the reference configuration.
void track_pose_velocity(const RobotModel& model, ControllerState& s, const RobotInput& in,
                         double sim_time_s, EventQueue* ev, JointVector& qd) {
  const int n = model.n;
  const IkParams& ik = model.ik;
  // task error at the reference configuration, plus the feed-forward twist
  forward_kinematics(model, s.q_ref, s.ref_frames);
  geometric_jacobian(model, s.ref_frames, s.ref_jacobian);
  const Vector6d e =
      pose_error(in.target_position_m, in.target_orientation.normalized().toRotationMatrix(),
                 s.ref_frames.tip.translation(), s.ref_frames.tip.linear());
  Eigen::Vector3d v = in.target_velocity_mps + ik.gain_per_s * e.head<3>();
  Eigen::Vector3d w = in.target_angular_velocity_radps + ik.gain_per_s * e.tail<3>();
  if (v.norm() > ik.max_tip_speed_mps) v *= ik.max_tip_speed_mps / v.norm();
  if (w.norm() > ik.max_tip_angular_speed_radps) w *= ik.max_tip_angular_speed_radps / w.norm();

  // weighted task: angular rows scaled by a length so that all rows are in metres
  const bool orient = in.track_orientation && ik.orientation_weight_m > 0.0;
  const int m = orient ? 6 : 3;
  const double L = ik.orientation_weight_m;
  TaskMatrix Jw(m, n);
  TaskVector xd(m);
  Jw.topRows(3) = s.ref_jacobian.topRows(3);
  xd.head(3) = v;
  if (orient) {
    Jw.bottomRows(3) = L * s.ref_jacobian.bottomRows(3);
    xd.tail(3) = L * w;
  }

  // smallest singular value from the smaller Gram matrix
  const int r = std::min(m, n);
  TaskMatrix G(r, r);
  if (m >= n) {
    G.noalias() = Jw.transpose() * Jw;
  } else {
    G.noalias() = Jw * Jw.transpose();
  }
  Eigen::SelfAdjointEigenSolver<TaskMatrix> es(G, Eigen::EigenvaluesOnly);
  const double sigma2 = std::max(0.0, es.eigenvalues().minCoeff());
  s.sigma_min_m = std::sqrt(sigma2);

  // variable damping: zero away from singularities, up to damping_max at sigma = 0
  const double lambda2 = singular_damping2(ik, s, sim_time_s, ev);

  G.diagonal().array() += lambda2;
  if (m >= n) {
    // qd = (Jw^T Jw + l^2 I)^-1 Jw^T xd
    JointVector rhs(n);
    rhs.noalias() = Jw.transpose() * xd;
    Eigen::LDLT<TaskMatrix> ldlt(G);
    qd = ldlt.solve(rhs);
  } else {
    // qd = Jw^T (Jw Jw^T + l^2 I)^-1 xd
    Eigen::LDLT<TaskMatrix> ldlt(G);
    TaskVector y(m);
    y = ldlt.solve(xd);
    qd.noalias() = Jw.transpose() * y;
  }
}

// Joint speed limits (the whole vector scaled, keeping its direction), then the reference
// integrated over dt_s and clamped to the joint limits minus a margin (events on entering a
// limit). Sets s.q_ref, s.qd_ref, s.limit_mask, s.speed_clamped.
void advance_reference(const RobotModel& model, ControllerState& s, JointVector& qd, double dt_s,
                       double sim_time_s, EventQueue* ev) {
  const int n = model.n;
  // joint speed limits: scale the whole vector, keeping the direction
  double scale = 1.0;
  for (int i = 0; i < n; ++i) {
    scale = std::max(scale, std::abs(qd(i)) / model.links[i].qd_max_radps);
  }
  s.speed_clamped = scale > 1.0;
  qd /= scale;

  // integrate and clamp to the limits (minus a margin)
  std::uint32_t mask = 0;
  for (int i = 0; i < n; ++i) {
    const LinkModel& l = model.links[i];
    const double lo = l.q_min_rad + model.ik.limit_margin_rad;
    const double hi = l.q_max_rad - model.ik.limit_margin_rad;
    double qn = s.q_ref(i) + qd(i) * dt_s;
    if (qn <= lo || qn >= hi) {
      qn = std::clamp(qn, lo, hi);
      qd(i) = 0.0;
      mask |= 1u << i;
      if (!(s.limit_mask & (1u << i))) {
        ++s.limit_events;
        if (ev) {
          char msg[96];
          std::snprintf(msg, sizeof(msg),
                        "robot joint %d reference clamped at its limit (%.3f rad)", i + 1, qn);
          ev->push(EventKind::kLimit, Severity::kWarning, sim_time_s, static_cast<double>(i + 1),
                   msg);
        }
      }
    }
    s.q_ref(i) = qn;
  }
  s.limit_mask = mask;
  s.qd_ref = qd;
}

// The joint command: PD gains and feed-forward (gravity, friction) at the measured configuration.
void fill_command(const RobotModel& model, const ControllerState& s, const RobotInput& in,
                  const Frames& measured_frames, JointCommand& out) {
  const int n = model.n;
  const IkParams& ik = model.ik;
  out.q_ref = s.q_ref;
  out.qd_ref = s.qd_ref;
  const double g = std::clamp(in.gain_scale, 0.0, 10.0);
  out.kp.resize(n);
  out.kd.resize(n);
  for (int i = 0; i < n; ++i) {
    const bool pd = in.mode != ControlMode::kPassive;
    out.kp(i) = pd ? g * model.links[i].kp_nm_per_rad : 0.0;
    out.kd(i) = pd ? std::sqrt(g) * model.links[i].kd_nms_per_rad : 0.0;
  }
  if (in.gravity_compensation) {
    gravity_torque(model, measured_frames, out.tau_gravity);
  } else {
    out.tau_gravity.setZero(n);
  }
  out.tau_ff = out.tau_gravity;
  if (in.mode != ControlMode::kPassive && ik.friction_compensation > 0.0) {
    for (int i = 0; i < n; ++i) {
      const LinkModel& l = model.links[i];
      out.tau_ff(i) += ik.friction_compensation *
                       (l.viscous_nms_per_rad * s.qd_ref(i) +
                        l.coulomb_nm * std::tanh(s.qd_ref(i) / ik.friction_velocity_radps));
    }
  }
}

}  // namespace

void controller_reset(const RobotModel& model, ControllerState& state, const JointVector& q) {
  state.q_ref = q;
  state.qd_ref.setZero(model.n);
  forward_kinematics(model, state.q_ref, state.ref_frames);
  geometric_jacobian(model, state.ref_frames, state.ref_jacobian);
  state.sigma_min_m = 0.0;
  state.damping_m = 0.0;
  state.near_singular = false;
  state.limit_mask = 0;
  state.speed_clamped = false;
}

void controller_update(const RobotModel& model, ControllerState& s, const RobotInput& in,
                       const JointVector& q, const Frames& measured_frames, double dt_s,
                       double sim_time_s, EventQueue* ev, JointCommand& out) {
  const int n = model.n;
  JointVector qd = JointVector::Zero(n);

  if (in.mode == ControlMode::kTrackPose) {
    track_pose_velocity(model, s, in, sim_time_s, ev, qd);
  } else if (in.mode == ControlMode::kJointTarget && in.target_q.size() == n) {
    for (int i = 0; i < n; ++i) {
      const double step = model.links[i].qd_max_radps * dt_s;
      const double d = std::clamp(in.target_q(i) - s.q_ref(i), -step, step);
      qd(i) = d / dt_s;
    }
  } else if (in.mode == ControlMode::kPassive) {
    // the reference follows the measured joints so that PD resumes without a jump
    s.q_ref = q;
  }
  // kHold: qd stays zero, q_ref unchanged

  // guard against non-finite reference velocities (a degenerate target)
  if (!qd.allFinite()) qd.setZero(n);
  advance_reference(model, s, qd, dt_s, sim_time_s, ev);
  fill_command(model, s, in, measured_frames, out);
}

void joint_torque(const RobotModel& model, const JointCommand& cmd, const JointVector& q,
                  const JointVector& qd, JointVector& tau) {
  tau.resize(model.n);
  for (int i = 0; i < model.n; ++i) {
    const double t =
        cmd.kp(i) * (cmd.q_ref(i) - q(i)) + cmd.kd(i) * (cmd.qd_ref(i) - qd(i)) + cmd.tau_ff(i);
    const double lim = model.links[i].torque_limit_nm;
    tau(i) = std::clamp(t, -lim, lim);
  }
}

}  // namespace teleop::sim::robot
