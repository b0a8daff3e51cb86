#pragma once
// Where a master maps its origin in the slave world it is sent (SceneDescription): the point
// where the tip centre is when its surface just touches the target surface. teleop_master uses
// it unless told a contact point; the in-process campaigns use it for the same mapping.
#include <Eigen/Core>

#include "common/dds/teleop_idl.hpp"

namespace teleop::dds {

/// The tip centre touching the top of the first deformable body (its highest node where the
/// server says: a body that sagged at load; else the top of its bounding sphere), else the
/// floor (an upward plane) under `tip_m`, else `tip_m` itself [m]. `scene` may be null (none
/// received): `tip_m`.
inline Eigen::Vector3d scene_contact_point(const SceneDescription* scene,
                                           const Eigen::Vector3d& tip_m) {
  if (!scene) return tip_m;
  const double r = scene->tip_radius_m() > 0 ? scene->tip_radius_m() : 0.05;
  for (const auto& o : scene->objects()) {
    if (o.kind() == OBJECT_DEFORMABLE_MESH && o.size_m()[0] > 0.0) {
      const double top = o.size_m()[1] > 0.0 ? o.size_m()[1] : o.size_m()[0];
      return Eigen::Vector3d(o.position_m()[0], o.position_m()[1], o.position_m()[2] + top + r);
    }
  }
  for (const auto& o : scene->objects()) {
    if (o.kind() == OBJECT_PLANE && o.normal()[2] > 0.99) {
      return Eigen::Vector3d(tip_m.x(), tip_m.y(), o.offset_m() + r);
    }
  }
  return tip_m;
}

}  // namespace teleop::dds
