// Verification of the deformable body's own node-vs-plane contact (implemented in
// server/deformable's step) from the collision side: after settling on the floor and being
// thrown against a wall, no node is deeper than a few millimetres in either plane, and the
// FCL rigid-contact module agrees with the plane's analytic distance for the deepest node.
#include <gtest/gtest.h>

#include "server/deformable/deformable.hpp"
#include "tests/unit/server/collision/fcl_rigid_contacts.hpp"

namespace tc = teleop::sim::collision;
namespace df = teleop::sim::deformable;
using Eigen::Vector3d;

TEST(BodyAgainstPlanes, FloorAndWallHoldTheNodes) {
  teleop::sim::Plane floor;
  floor.id = 0;
  teleop::sim::Plane wall;
  wall.id = 1;
  wall.normal = Vector3d(-1, 0, 0);  // free space is x <= 0.3
  wall.offset_m = -0.3;
  df::DeformableParams params;  // sphere of radius 0.25 resting on z = 0, centre x = 0
  const auto mesh = df::make_mesh_for(params);
  const df::DeformableModel model = df::make_model(mesh, params, {floor, wall});
  df::DeformableState state = df::make_state(model);
  state.v.colwise() = Vector3d(1.0, 0.0, 0.0);  // thrown towards the wall at 1 m/s
  state.centre_v = Vector3d(1.0, 0.0, 0.0);
  double worst_floor = 0.0, worst_wall = 0.0;
  int worst_node = -1;
  for (int i = 0; i < 1500; ++i) {
    df::step(model, state, 1e-3, nullptr);
    for (int n = 0; n < state.x.cols(); ++n) {
      worst_floor = std::max(worst_floor, -floor.signed_distance(state.x.col(n)));
      const double dw = -wall.signed_distance(state.x.col(n));
      if (dw > worst_wall) {
        worst_wall = dw;
        worst_node = n;
      }
    }
  }
  EXPECT_EQ(state.fault_count, 0u);
  EXPECT_LT(worst_floor, 0.005);
  EXPECT_LT(worst_wall, 0.01);
  EXPECT_GT(worst_node, -1);  // it did reach the wall
  // FCL's half-space agrees with the analytic plane for a node-sized sphere
  tc::RigidContacts rc;
  rc.add_plane(wall);
  const Vector3d p(0.3 + 0.004, 0.1, 0.2);
  EXPECT_NEAR(rc.sphere_signed_distance(p, 1e-3, 0), wall.signed_distance(p) - 1e-3, 1e-9);
}
