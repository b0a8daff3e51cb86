// Kinematics of the slave chain: eqs. (4)-(6) against finite differences and virtual work.
#include "server/robot/kinematics.hpp"

#include <gtest/gtest.h>

#include <random>

#include "tests/support/alloc_counter.hpp"
#include "tests/unit/server/robot/robot_test_util.hpp"

namespace teleop::sim::robot {
namespace {

JointVector random_q(const RobotModel& m, std::mt19937& rng) {
  JointVector q(m.n);
  for (int i = 0; i < m.n; ++i) {
    std::uniform_real_distribution<double> u(m.links[i].q_min_rad, m.links[i].q_max_rad);
    q(i) = u(rng);
  }
  return q;
}

Eigen::Vector3d tip_pos(const RobotModel& m, const JointVector& q) {
  Frames f;
  forward_kinematics(m, q, f);
  return f.tip.translation();
}

Eigen::Matrix3d tip_rot(const RobotModel& m, const JointVector& q) {
  Frames f;
  forward_kinematics(m, q, f);
  return f.tip.linear();
}

TEST(RobotKinematics, PumaZeroPoseMatchesToolboxForwardKinematics) {
  // Robotics Toolbox: p560.fkine(qz) has the flange at (0.4521, -0.1500, 0.4318) m, R = I
  RobotModel m = testing::puma();
  m.base = Eigen::Isometry3d::Identity();
  m.tool_offset_m.setZero();
  Frames f;
  forward_kinematics(m, JointVector::Zero(6), f);
  EXPECT_NEAR(f.tip.translation().x(), 0.4521, 1e-4);
  EXPECT_NEAR(f.tip.translation().y(), -0.1500, 1e-4);
  EXPECT_NEAR(f.tip.translation().z(), 0.4318, 1e-4);
  EXPECT_LT((f.tip.linear() - Eigen::Matrix3d::Identity()).norm(), 1e-9);
}

TEST(RobotKinematics, JacobianMatchesFiniteDifferences) {
  const RobotModel m = testing::puma();
  std::mt19937 rng(7);
  const double h = 1e-6;
  for (int trial = 0; trial < 20; ++trial) {
    const JointVector q = random_q(m, rng);
    Jacobian J;
    geometric_jacobian(m, q, J);
    for (int i = 0; i < m.n; ++i) {
      JointVector qp = q, qm = q;
      qp(i) += h;
      qm(i) -= h;
      const Eigen::Vector3d dp = (tip_pos(m, qp) - tip_pos(m, qm)) / (2 * h);
      const Eigen::Vector3d dw =
          rotation_vector(tip_rot(m, qp) * tip_rot(m, qm).transpose()) / (2 * h);
      EXPECT_LT((J.block<3, 1>(0, i) - dp).norm(), 1e-6) << "trial " << trial << " joint " << i;
      EXPECT_LT((J.block<3, 1>(3, i) - dw).norm(), 1e-6) << "trial " << trial << " joint " << i;
    }
  }
}

TEST(RobotKinematics, TipVelocityIsJacobianTimesJointRates) {
  const RobotModel m = testing::puma();
  std::mt19937 rng(11);
  std::normal_distribution<double> nd(0.0, 1.0);
  const double h = 1e-6;
  for (int trial = 0; trial < 10; ++trial) {
    const JointVector q = random_q(m, rng);
    JointVector qd(m.n);
    for (int i = 0; i < m.n; ++i) qd(i) = nd(rng);
    Jacobian J;
    geometric_jacobian(m, q, J);
    const Vector6d v = tip_twist(J, qd);
    const Eigen::Vector3d fd = (tip_pos(m, q + h * qd) - tip_pos(m, q - h * qd)) / (2 * h);
    const Eigen::Vector3d wd =
        rotation_vector(tip_rot(m, q + h * qd) * tip_rot(m, q - h * qd).transpose()) / (2 * h);
    EXPECT_LT((v.head<3>() - fd).norm(), 1e-6 * (1 + fd.norm()));
    EXPECT_LT((v.tail<3>() - wd).norm(), 1e-6 * (1 + wd.norm()));
  }
}

TEST(RobotKinematics, JointTorqueOfTipWrenchSatisfiesVirtualWork) {
  // tau = J^T gamma (eq. 4): the work tau . dq equals f . dp + m . dtheta of the tip motion
  const RobotModel m = testing::puma();
  std::mt19937 rng(3);
  std::normal_distribution<double> nd(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    const JointVector q = random_q(m, rng);
    Vector6d gamma;
    for (int k = 0; k < 6; ++k) gamma(k) = 10.0 * nd(rng);
    Jacobian J;
    geometric_jacobian(m, q, J);
    JointVector tau;
    wrench_to_joint_torque(J, gamma, tau);
    JointVector dq(m.n);
    for (int i = 0; i < m.n; ++i) dq(i) = 1e-7 * nd(rng);
    const Eigen::Vector3d dp = tip_pos(m, q + dq) - tip_pos(m, q);
    const Eigen::Vector3d dth = rotation_vector(tip_rot(m, q + dq) * tip_rot(m, q).transpose());
    const double work_joint = tau.dot(dq);
    const double work_tip = gamma.head<3>().dot(dp) + gamma.tail<3>().dot(dth);
    EXPECT_NEAR(work_joint, work_tip, 1e-4 * std::abs(work_joint) + 1e-12) << trial;
  }
}

TEST(RobotKinematics, GravityTorqueIsGradientOfPotentialEnergy) {
  const RobotModel m = testing::puma();
  auto potential = [&](const JointVector& q) {
    Frames f;
    forward_kinematics(m, q, f);
    double v = 0.0;
    for (int i = 0; i < m.n; ++i) v -= m.links[i].mass_kg * m.gravity_mps2.dot(f.com[i]);
    return v;
  };
  std::mt19937 rng(5);
  const double h = 1e-6;
  for (int trial = 0; trial < 10; ++trial) {
    const JointVector q = random_q(m, rng);
    Frames f;
    forward_kinematics(m, q, f);
    JointVector tau;
    gravity_torque(m, f, tau);
    for (int i = 0; i < m.n; ++i) {
      JointVector qp = q, qm = q;
      qp(i) += h;
      qm(i) -= h;
      const double grad = (potential(qp) - potential(qm)) / (2 * h);
      EXPECT_NEAR(tau(i), grad, 1e-5 * (1 + std::abs(grad))) << trial << " joint " << i;
    }
  }
}

TEST(RobotKinematics, LinkBoxPosesFollowTheLinkFrames) {
  const RobotModel m = testing::puma();
  Frames f;
  forward_kinematics(m, m.q_home, f);
  std::array<Eigen::Isometry3d, kMaxJoints> boxes;
  link_box_poses(m, f, boxes);
  for (int i = 0; i < m.n; ++i) {
    EXPECT_LT((boxes[i].translation() - f.T[i + 1] * m.links[i].box_center_m).norm(), 1e-12);
    EXPECT_LT((boxes[i].linear() - f.T[i + 1].linear()).norm(), 1e-12);
  }
  // the forearm box (link 3) lies between the elbow and the wrist centre
  const Eigen::Vector3d elbow = f.T[2].translation(), wrist = f.T[4].translation();
  const Eigen::Vector3d mid = 0.5 * (elbow + wrist);
  EXPECT_LT((boxes[2].translation() - mid).norm(), 0.12);
}

TEST(RobotKinematics, KinematicsDoNotAllocate) {
  const RobotModel m = testing::puma();
  JointVector q = m.q_home;
  Frames f;
  Jacobian J;
  JointVector tau;
  Vector6d w = Vector6d::Ones();
  teleop::test::NoAllocScope scope;
  for (int k = 0; k < 10; ++k) {
    forward_kinematics(m, q, f);
    geometric_jacobian(m, f, J);
    wrench_to_joint_torque(J, w, tau);
    gravity_torque(m, f, tau);
    q(0) += 0.01;
  }
  EXPECT_EQ(scope.allocations(), 0u);
}

}  // namespace
}  // namespace teleop::sim::robot
