#include "server/robot/kinematics.hpp"

#include <cmath>

namespace teleop::sim::robot {

Eigen::Isometry3d dh_transform(const DhParams& dh, double q_rad) {
  const double th = q_rad + dh.theta_offset_rad;
  const double ct = std::cos(th), st = std::sin(th);
  const double ca = std::cos(dh.alpha_rad), sa = std::sin(dh.alpha_rad);
  // Rz(th) Tz(d) Tx(a) Rx(alpha)
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  Eigen::Matrix3d R;
  R << ct, -st * ca, st * sa,  //
      st, ct * ca, -ct * sa,   //
      0.0, sa, ca;
  T.linear() = R;
  T.translation() << dh.a_m * ct, dh.a_m * st, dh.d_m;
  return T;
}

void forward_kinematics(const RobotModel& model, const JointVector& q, Frames& out) {
  out.n = model.n;
  out.T[0] = model.base;
  for (int i = 0; i < model.n; ++i) {
    out.T[i + 1] = out.T[i] * dh_transform(model.links[i].dh, q(i));
    out.com[i] = out.T[i + 1] * model.links[i].com_m;
  }
  out.tip.linear() = out.T[model.n].linear();
  out.tip.translation() = out.T[model.n] * model.tool_offset_m;
}

void geometric_jacobian(const RobotModel& model, const Frames& frames, Jacobian& J) {
  J.resize(6, model.n);
  const Eigen::Vector3d P = frames.tip.translation();
  for (int i = 0; i < model.n; ++i) {
    // joint i+1 turns about z_i through the origin of frame i
    const Eigen::Vector3d z = frames.T[i].linear().col(2);
    const Eigen::Vector3d p = frames.T[i].translation();
    J.block<3, 1>(0, i) = z.cross(P - p);
    J.block<3, 1>(3, i) = z;
  }
}

void geometric_jacobian(const RobotModel& model, const JointVector& q, Jacobian& J) {
  Frames f;
  forward_kinematics(model, q, f);
  geometric_jacobian(model, f, J);
}

Vector6d tip_twist(const Jacobian& J, const JointVector& qd) { return J * qd; }

void wrench_to_joint_torque(const Jacobian& J, const Vector6d& wrench, JointVector& tau) {
  tau.noalias() = J.transpose() * wrench;
}

void gravity_torque(const RobotModel& model, const Frames& frames, JointVector& tau) {
  tau.setZero(model.n);
  for (int j = 0; j < model.n; ++j) {
    const Eigen::Vector3d z = frames.T[j].linear().col(2);
    const Eigen::Vector3d p = frames.T[j].translation();
    // every link from j on is moved by joint j+1; its weight m g acts at its COM
    double t = 0.0;
    for (int i = j; i < model.n; ++i) {
      const Eigen::Vector3d weight = model.links[i].mass_kg * model.gravity_mps2;
      t += z.cross(frames.com[i] - p).dot(weight);
    }
    tau(j) = -t;  // the actuator cancels the gravity torque
  }
}

void link_box_poses(const RobotModel& model, const Frames& frames,
                    std::array<Eigen::Isometry3d, kMaxJoints>& out) {
  for (int i = 0; i < model.n; ++i) {
    out[i].linear() = frames.T[i + 1].linear();
    out[i].translation() = frames.T[i + 1] * model.links[i].box_center_m;
    out[i].makeAffine();
  }
}

Eigen::Vector3d rotation_vector(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  double angle = aa.angle();
  Eigen::Vector3d axis = aa.axis();
  if (angle > M_PI) {
    angle = 2.0 * M_PI - angle;
    axis = -axis;
  }
  return angle * axis;
}

Vector6d pose_error(const Eigen::Vector3d& p_d, const Eigen::Matrix3d& R_d,
                    const Eigen::Vector3d& p, const Eigen::Matrix3d& R) {
  Vector6d e;
  e.head<3>() = p_d - p;
  e.tail<3>() = rotation_vector(R_d * R.transpose());
  return e;
}

}  // namespace teleop::sim::robot
