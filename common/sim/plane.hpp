#pragma once
// Rigid planes (floor, walls): modelled as half-spaces, never as meshes.
#include <Eigen/Core>
#include <string>

namespace teleop::sim {

/// Most planes a scene may hold (the tool law's obstacle array has this many slots).
inline constexpr int kMaxPlanes = 8;

/// Penalty damping of plane contacts ramps in linearly over this depth, so the contact force is
/// continuous at onset (no b*v step when a moving tool first touches) [m].
inline constexpr double kPlaneDampingRampM = 1e-3;

/// A rigid half-space boundary: points x with normal.dot(x) >= offset are free space.
struct Plane {
  int id = -1;  ///< SceneObject id
  std::string name;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< unit normal pointing into free space
  double offset_m = 0.0;                              ///< normal . x = offset on the surface [m]
  double stiffness_n_per_m = 2.0e4;                   ///< penalty stiffness k [N/m]
  double damping_ns_per_m = 50.0;  ///< penalty damping (compression only) [N s/m]
  double friction = 0.3;           ///< Coulomb coefficient [-]

  /// Signed distance of point x from the plane surface [m] (negative inside the wall).
  double signed_distance(const Eigen::Vector3d& x) const { return normal.dot(x) - offset_m; }
};

}  // namespace teleop::sim
