// The FCL rigid contacts (the collision tests' independent reference) against analytic
// sphere-plane, sphere-box and box-box formulas.
#include "tests/unit/server/collision/fcl_rigid_contacts.hpp"

#include <gtest/gtest.h>

#include <random>

namespace tc = teleop::sim::collision;
using Eigen::Vector3d;

namespace {

// analytic signed distance of a sphere to a box (world pose), and the push-out normal
double sphere_box_signed(const Vector3d& c, double r, const Vector3d& half,
                         const Eigen::Isometry3d& pose, Vector3d* normal) {
  const Vector3d local = pose.inverse() * c;
  const Vector3d q = local.cwiseAbs() - half;
  double sd;
  Vector3d nl;
  if ((q.array() > 0.0).any()) {
    const Vector3d clamped = local.cwiseMax(-half).cwiseMin(half);
    nl = (local - clamped).normalized();
    sd = (local - clamped).norm();
  } else {
    int axis;
    q.maxCoeff(&axis);
    sd = q[axis];
    nl = Vector3d::Zero();
    nl[axis] = local[axis] >= 0 ? 1.0 : -1.0;
  }
  if (normal) *normal = pose.linear() * nl;
  return sd - r;
}

}  // namespace

TEST(RigidContacts, SpherePlaneMatchesAnalytic) {
  tc::RigidContacts rc;
  teleop::sim::Plane floor;
  floor.id = 7;
  floor.normal = Vector3d(0, 0, 1);
  floor.offset_m = 0.0;
  teleop::sim::Plane wall;
  wall.id = 8;
  wall.normal = Vector3d(-1, 1, 0).normalized();
  wall.offset_m = -0.8;
  rc.add_plane(floor);
  rc.add_plane(wall);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  std::vector<tc::RigidContact> out;
  for (int i = 0; i < 200; ++i) {
    const Vector3d c(u(rng), u(rng), 0.1 * u(rng));
    const double r = 0.05;
    rc.query_sphere(c, r, out);
    const double depth_floor = r - floor.signed_distance(c);
    const double depth_wall = r - wall.signed_distance(c);
    int expect = (depth_floor > 0) + (depth_wall > 0);
    ASSERT_EQ(static_cast<int>(out.size()), expect) << c.transpose();
    for (const auto& ct : out) {
      const teleop::sim::Plane& pl = ct.object_id == 7 ? floor : wall;
      EXPECT_NEAR(ct.depth_m, r - pl.signed_distance(c), 1e-9);
      EXPECT_NEAR((ct.normal - pl.normal).norm(), 0.0, 1e-9);
    }
    EXPECT_NEAR(rc.sphere_signed_distance(c, r, 0), floor.signed_distance(c) - r, 1e-9);
  }
}

TEST(RigidContacts, SphereBoxMatchesAnalyticAndPoseUpdatesAreSeen) {
  tc::RigidContacts rc;
  const Vector3d half(0.2, 0.1, 0.05);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translate(Vector3d(0.3, -0.1, 0.2));
  pose.rotate(Eigen::AngleAxisd(0.4, Vector3d(1, 2, 3).normalized()));
  const int idx = rc.add_box(3, half, pose);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-0.35, 0.35);
  std::vector<tc::RigidContact> out;
  int hits = 0, checked_apart = 0;
  for (int i = 0; i < 400; ++i) {
    const Vector3d c = pose.translation() + Vector3d(u(rng), u(rng), u(rng));
    const double r = 0.05;
    Vector3d n;
    const double sd = sphere_box_signed(c, r, half, pose, &n);
    rc.query_sphere(c, r, out);
    if (sd < -1e-6) {
      ASSERT_EQ(out.size(), 1u) << c.transpose();
      ++hits;
      // deep overlaps (centre inside the box) are where GJK/EPA is least exact
      const double tol = sd < -r ? 2e-3 : 1e-6;
      EXPECT_NEAR(out[0].depth_m, -sd, tol);
      if (sd > -r) {
        EXPECT_NEAR((out[0].normal - n).norm(), 0.0, 1e-4);
      }
    } else if (sd > 1e-6) {
      EXPECT_TRUE(out.empty());
      EXPECT_NEAR(rc.sphere_signed_distance(c, r, idx), sd, 1e-6);
      ++checked_apart;
    }
  }
  EXPECT_GT(hits, 30);
  EXPECT_GT(checked_apart, 30);
  // move the box: the cached bounding box must follow (FCL pitfall)
  Eigen::Isometry3d moved = pose;
  moved.translation() += Vector3d(5, 0, 0);
  rc.set_pose(idx, moved);
  rc.query_sphere(pose.translation(), 0.05, out);
  EXPECT_TRUE(out.empty());
  rc.query_sphere(moved.translation(), 0.05, out);
  EXPECT_EQ(out.size(), 1u);
}

TEST(RigidContacts, BoxOnPlane) {
  tc::RigidContacts rc;
  teleop::sim::Plane floor;
  floor.id = 1;
  rc.add_plane(floor);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = Vector3d(0.0, 0.0, 0.04);
  std::vector<tc::RigidContact> out;
  rc.query_box(Vector3d(0.1, 0.1, 0.05), pose, out);
  ASSERT_FALSE(out.empty());
  EXPECT_NEAR(out[0].depth_m, 0.01, 1e-9);
  EXPECT_NEAR(out[0].normal.z(), 1.0, 1e-9);
  pose.translation().z() = 0.06;
  rc.query_box(Vector3d(0.1, 0.1, 0.05), pose, out);
  EXPECT_TRUE(out.empty());
}

TEST(RigidContacts, BoxAgainstBox) {
  tc::RigidContacts rc;
  rc.add_box(5, Vector3d(0.1, 0.1, 0.1), Eigen::Isometry3d::Identity());
  std::vector<tc::RigidContact> out;
  for (const double gap : {-0.02, -0.005, 0.01}) {
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Vector3d(0.1 + 0.05 + gap, 0.02, -0.01);  // query half extent 0.05
    rc.query_box(Vector3d(0.05, 0.05, 0.05), pose, out);
    if (gap < 0.0) {
      ASSERT_FALSE(out.empty()) << gap;
      double deepest = 0.0;
      for (const auto& c : out) {
        deepest = std::max(deepest, c.depth_m);
        EXPECT_EQ(c.object_id, 5);
        EXPECT_GT(c.normal.x(), 0.99);  // pushed out along +x
      }
      EXPECT_NEAR(deepest, -gap, 1e-6);
    } else {
      EXPECT_TRUE(out.empty());
    }
  }
}
