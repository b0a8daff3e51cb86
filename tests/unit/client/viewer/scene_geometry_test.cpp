#include "client/viewer/scene_geometry.hpp"

#include <gtest/gtest.h>

#include <vector>

#include <Eigen/Geometry>

namespace teleop::viewer {
namespace {

// the tool-only scene's box: floor z >= 0, walls at x = -0.3 and 1.2, y = +-0.8
std::vector<Plane> box() {
  return {Plane{Eigen::Vector3f(0, 0, 1), 0.0f}, Plane{Eigen::Vector3f(-1, 0, 0), -1.2f},
          Plane{Eigen::Vector3f(1, 0, 0), -0.3f}, Plane{Eigen::Vector3f(0, -1, 0), -0.8f},
          Plane{Eigen::Vector3f(0, 1, 0), -0.8f}};
}

TEST(PlanePatch, TheFloorEndsAtTheWallsAndTheWallsAtTheFloor) {
  const Bounds b{Eigen::Vector3f(-1.0f, -1.5f, -0.4f), Eigen::Vector3f(2.0f, 1.5f, 1.8f)};
  const auto planes = box();
  const PlanePatch floor = make_plane_patch(planes, 0, b, 0.1f);
  ASSERT_EQ(floor.polygon.size(), 4u);
  for (const auto& p : floor.polygon) {
    EXPECT_NEAR(p.z(), 0.0f, 1e-5f);
    EXPECT_GE(p.x(), -0.3f - 1e-3f);
    EXPECT_LE(p.x(), 1.2f + 1e-3f);
    EXPECT_LE(std::abs(p.y()), 0.8f + 1e-3f);
  }
  // counter-clockwise seen from above
  const Eigen::Vector3f n =
      (floor.polygon[1] - floor.polygon[0]).cross(floor.polygon[2] - floor.polygon[0]);
  EXPECT_GT(n.z(), 0.0f);
  // grid lines every 0.1 m, all on the patch
  EXPECT_GE(floor.grid.size(), 15u + 16u);
  for (const auto& seg : floor.grid) {
    for (const auto& p : seg) {
      EXPECT_GE(p.x(), -0.3f - 1e-3f);
      EXPECT_LE(p.x(), 1.2f + 1e-3f);
    }
  }
  const PlanePatch far_wall = make_plane_patch(planes, 1, b, 0.1f);
  ASSERT_GE(far_wall.polygon.size(), 3u);
  for (const auto& p : far_wall.polygon) {
    EXPECT_NEAR(p.x(), 1.2f, 1e-5f);
    EXPECT_GE(p.z(), -1e-3f);
    EXPECT_LE(p.z(), 1.8f + 1e-3f);
  }
}

TEST(Primitives, SphereNormalsPointOutwardAndTrianglesAreCounterClockwise) {
  const PrimitiveMesh s = make_sphere(2);
  EXPECT_EQ(s.indices.size(), 3u * 20u * 16u);
  for (std::size_t k = 0; k < s.indices.size(); k += 3) {
    const auto& a = s.positions[s.indices[k]];
    const auto& b = s.positions[s.indices[k + 1]];
    const auto& c = s.positions[s.indices[k + 2]];
    EXPECT_GT((b - a).cross(c - a).dot(a + b + c), 0.0f) << "triangle " << k / 3;
  }
  for (std::size_t i = 0; i < s.positions.size(); ++i) {
    EXPECT_NEAR(s.positions[i].norm(), 1.0f, 1e-5f);
    EXPECT_NEAR(s.normals[i].dot(s.positions[i]), 1.0f, 1e-5f);
  }
  for (const PrimitiveMesh& m : {make_cylinder(12), make_cone(12)}) {
    for (std::size_t k = 0; k < m.indices.size(); k += 3) {
      const auto& a = m.positions[m.indices[k]];
      const auto& b = m.positions[m.indices[k + 1]];
      const auto& c = m.positions[m.indices[k + 2]];
      const Eigen::Vector3f centroid = (a + b + c) / 3.0f - Eigen::Vector3f(0, 0, 0.5f);
      EXPECT_GT((b - a).cross(c - a).dot(centroid), 0.0f) << "triangle " << k / 3;
    }
  }
}

TEST(VertexNormals, OfATetrahedronPointAwayFromItsCentre) {
  const float p[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
  const std::uint32_t t[] = {0, 2, 1, 0, 1, 3, 1, 2, 3, 0, 3, 2};
  float n[12];
  vertex_normals(p, 4, t, 4, n);
  const Eigen::Vector3f centre(0.25f, 0.25f, 0.25f);
  for (int i = 0; i < 4; ++i) {
    const Eigen::Map<const Eigen::Vector3f> v(p + 3 * i), vn(n + 3 * i);
    EXPECT_NEAR(vn.norm(), 1.0f, 1e-5f);
    EXPECT_GT(vn.dot(v - centre), 0.0f) << "vertex " << i;
  }
}

TEST(DisplacementColor, BlueAtRestRedAtTheScale) {
  EXPECT_GT(displacement_color(0.0f, 0.02f).z(), 0.7f);
  EXPECT_GT(displacement_color(0.05f, 0.02f).x(), 0.7f);
  EXPECT_LT(displacement_color(0.05f, 0.02f).z(), 0.2f);
}

// A ball of points rolled by 20 degrees and moved 3 cm leaves no deformation once the best rigid
// motion is taken out; a 4 mm dent at one point is all that is left.
TEST(RigidFit, TakesOutARollAndAShiftAndLeavesTheDent) {
  std::vector<float> rest, moved;
  const Eigen::Matrix3f roll =
      Eigen::AngleAxisf(0.35f, Eigen::Vector3f(1.0f, 2.0f, 0.5f).normalized()).toRotationMatrix();
  const Eigen::Vector3f centre(0.6f, 0.0f, 0.25f), shift(0.03f, -0.01f, -0.004f);
  for (int i = 0; i < 200; ++i) {  // points on a sphere of 0.25 m (a Fibonacci spiral)
    const float z = 1.0f - 2.0f * (static_cast<float>(i) + 0.5f) / 200.0f;
    const float r = std::sqrt(1.0f - z * z), a = 2.39996323f * static_cast<float>(i);
    const Eigen::Vector3f p = centre + 0.25f * Eigen::Vector3f(r * std::cos(a), r * std::sin(a), z);
    Eigen::Vector3f q = roll * (p - centre) + centre + shift;
    if (i == 0) q += 0.004f * (roll * Eigen::Vector3f::UnitZ());  // pushed in along its normal
    rest.insert(rest.end(), {p.x(), p.y(), p.z()});
    moved.insert(moved.end(), {q.x(), q.y(), q.z()});
  }
  const RigidFit fit = best_rigid_fit(rest.data(), moved.data(), 200);
  float dent = 0.0f, elsewhere = 0.0f, plain_largest = 0.0f;
  for (std::size_t i = 0; i < 200; ++i) {
    const Eigen::Map<const Eigen::Vector3f> p(rest.data() + 3 * i), q(moved.data() + 3 * i);
    const float d = (q - fit.apply(p)).norm();
    if (i == 0) {
      dent = d;
    } else {
      elsewhere = std::max(elsewhere, d);
    }
    plain_largest = std::max(plain_largest, (q - p).norm());
  }
  EXPECT_GT(plain_largest, 0.05f);  // the roll and shift alone move points by centimetres
  EXPECT_NEAR(dent, 0.004f, 0.0005f);
  EXPECT_LT(elsewhere, 0.0003f);
  EXPECT_NEAR(fit.rotation.determinant(), 1.0f, 1e-4f);
}

}  // namespace
}  // namespace teleop::viewer
