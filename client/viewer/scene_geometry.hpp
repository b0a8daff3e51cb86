#pragma once
// Geometry the renderer draws, built on the CPU without OpenGL: unit primitives, the visible
// patch of each (infinite) scene plane, vertex normals of a deforming mesh and the colour map of
// the displacement view.
#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace teleop::viewer {

/// A triangle mesh with per-vertex normals (counter-clockwise seen from outside).
struct PrimitiveMesh {
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector3f> normals;
  std::vector<std::uint32_t> indices;
};

/// Unit sphere (radius 1, centred at the origin) from a subdivided icosahedron.
PrimitiveMesh make_sphere(int subdivisions);
/// Cylinder of radius 1 from z = 0 to z = 1, with caps.
PrimitiveMesh make_cylinder(int segments);
/// Cone with a base of radius 1 at z = 0 and its apex at z = 1, with a base cap.
PrimitiveMesh make_cone(int segments);

/// A plane `normal . x = offset` whose free side (where objects live) is normal . x >= offset.
struct Plane {
  Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();
  float offset_m = 0.0f;
};

/// Axis-aligned box.
struct Bounds {
  Eigen::Vector3f min = Eigen::Vector3f::Constant(-1.0f);
  Eigen::Vector3f max = Eigen::Vector3f::Constant(1.0f);
};

/// The drawable part of a plane: a convex polygon and grid lines.
struct PlanePatch {
  Plane plane;
  std::vector<Eigen::Vector3f> polygon;  ///< convex, counter-clockwise seen from the free side
  std::vector<std::array<Eigen::Vector3f, 2>> grid;  ///< line segments on the patch
};

/// The patch of `planes[index]` inside `bounds`, cut by the free half-spaces of the other
/// planes (a floor ends at the walls, a wall at the floor), with grid lines every grid_step_m.
PlanePatch make_plane_patch(const std::vector<Plane>& planes, std::size_t index,
                            const Bounds& bounds, float grid_step_m);

/// Area-weighted vertex normals of a triangle mesh. positions and normals hold 3 floats per
/// vertex; triangles 3 indices each (all < vertex_count). Allocation-free.
void vertex_normals(const float* positions, std::size_t vertex_count,
                    const std::uint32_t* triangles, std::size_t triangle_count, float* normals);

/// Colour of a displacement d [m] on a blue-white-red scale saturating at scale_m.
Eigen::Vector3f displacement_color(float d_m, float scale_m);

/// A rigid motion p -> rotation (p - from_centroid) + to_centroid.
struct RigidFit {
  Eigen::Matrix3f rotation = Eigen::Matrix3f::Identity();
  Eigen::Vector3f from_centroid = Eigen::Vector3f::Zero();
  Eigen::Vector3f to_centroid = Eigen::Vector3f::Zero();
  Eigen::Vector3f apply(const Eigen::Vector3f& p) const {
    return rotation * (p - from_centroid) + to_centroid;
  }
};

/// The rigid motion that best maps the points `from` onto `to` in least squares (the Kabsch
/// solution, a proper rotation); what is left, |to - fit(from)|, is the body's deformation.
/// 3 floats per point. Allocation-free.
RigidFit best_rigid_fit(const float* from, const float* to, std::size_t count);

}  // namespace teleop::viewer
