#pragma once
// The collision tests' independent reference (test code: the world's rigid pairs, the tip and
// the deformable nodes against planes, are analytic and checked against this).
// Rigid contacts through FCL 0.7: the tip sphere (or a box) against the scene's planes
// (FCL half-spaces) and boxes. Results use one convention: `normal` is the unit direction
// that pushes the query shape out of the object (from the object towards the query), depth
// is the overlap [m] (> 0 when penetrating), point is FCL's contact point [m].
//
// FCL pitfalls handled here (see REFERENCE.md): an object's cached world AABB goes stale
// when its pose changes, so every pose change recomputes it; results are cross-checked
// against analytic sphere-plane / sphere-box formulas in tests. FCL allocates inside
// collide(): use this outside the 1 kHz hot loop or for rigid pairs only; the tip-vs-plane
// hot path has an analytic equivalent in the tool scene.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "common/sim/plane.hpp"

namespace teleop::sim::collision {

/// One contact between the query shape and a rigid object.
struct RigidContact {
  int object_id = -1;                                 ///< scene id of the object touched
  int object_index = -1;                              ///< index in RigidContacts (order of add_*)
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< push-out direction for the query
  double depth_m = 0.0;                               ///< penetration depth [m]
  Eigen::Vector3d point_m = Eigen::Vector3d::Zero();  ///< contact point [m]
};

/// A set of rigid objects (planes and boxes) queried with a sphere or a box.
class RigidContacts {
 public:
  RigidContacts();
  ~RigidContacts();
  RigidContacts(const RigidContacts&) = delete;
  RigidContacts& operator=(const RigidContacts&) = delete;

  /// Adds a plane (its solid side is normal.x < offset). @return the object's index.
  int add_plane(const Plane& plane);
  /// Adds a box with half extents [m] at `pose` (world from box). @return the index.
  int add_box(int object_id, const Eigen::Vector3d& half_extents_m, const Eigen::Isometry3d& pose);
  /// Moves box `index`; refreshes its cached AABB.
  void set_pose(int index, const Eigen::Isometry3d& pose);
  int object_count() const;

  /// Contacts of a sphere (centre c [m], radius r [m]) with every object; clears `out`.
  /// @return the number of contacts.
  int query_sphere(const Eigen::Vector3d& centre_m, double radius_m,
                   std::vector<RigidContact>& out) const;
  /// Contacts of a box (half extents [m], pose) with every object; clears `out`.
  int query_box(const Eigen::Vector3d& half_extents_m, const Eigen::Isometry3d& pose,
                std::vector<RigidContact>& out) const;

  /// Signed distance between a sphere and object `index` [m]: separation when apart,
  /// minus the penetration depth when overlapping.
  double sphere_signed_distance(const Eigen::Vector3d& centre_m, double radius_m, int index) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace teleop::sim::collision
