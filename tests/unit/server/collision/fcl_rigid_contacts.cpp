#include "tests/unit/server/collision/fcl_rigid_contacts.hpp"

#include <fcl/geometry/shape/box.h>
#include <fcl/geometry/shape/halfspace.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_object.h>
#include <fcl/narrowphase/distance.h>

#include <limits>

namespace teleop::sim::collision {

struct RigidContacts::Impl {
  struct Entry {
    int id = -1;
    std::unique_ptr<fcl::CollisionObjectd> object;
  };
  std::vector<Entry> entries;

  int query(fcl::CollisionObjectd& q, std::vector<RigidContact>& out) const {
    out.clear();
    fcl::CollisionRequestd req(8, true);
    for (std::size_t i = 0; i < entries.size(); ++i) {
      fcl::CollisionResultd res;
      fcl::collide(&q, entries[i].object.get(), req, res);
      for (std::size_t c = 0; c < res.numContacts(); ++c) {
        const auto& ct = res.getContact(c);
        RigidContact rc;
        rc.object_id = entries[i].id;
        rc.object_index = static_cast<int>(i);
        // FCL's normal points from o1 (the query) to o2 (the object): flip to push out
        rc.normal = -ct.normal.normalized();
        rc.depth_m = ct.penetration_depth;
        rc.point_m = ct.pos;
        out.push_back(rc);
      }
    }
    return static_cast<int>(out.size());
  }
};

RigidContacts::RigidContacts() : impl_(std::make_unique<Impl>()) {}
RigidContacts::~RigidContacts() = default;

int RigidContacts::add_plane(const Plane& plane) {
  // FCL's half-space is the solid set n.x <= d, exactly the wall side of our Plane
  auto geom = std::make_shared<fcl::Halfspaced>(plane.normal.normalized(), plane.offset_m);
  auto obj = std::make_unique<fcl::CollisionObjectd>(geom, fcl::Transform3d::Identity());
  obj->computeAABB();
  impl_->entries.push_back({plane.id, std::move(obj)});
  return static_cast<int>(impl_->entries.size()) - 1;
}

int RigidContacts::add_box(int object_id, const Eigen::Vector3d& half_extents_m,
                           const Eigen::Isometry3d& pose) {
  auto geom = std::make_shared<fcl::Boxd>(2.0 * half_extents_m);
  auto obj = std::make_unique<fcl::CollisionObjectd>(geom, fcl::Transform3d(pose.matrix()));
  obj->computeAABB();
  impl_->entries.push_back({object_id, std::move(obj)});
  return static_cast<int>(impl_->entries.size()) - 1;
}

void RigidContacts::set_pose(int index, const Eigen::Isometry3d& pose) {
  auto& obj = *impl_->entries.at(static_cast<std::size_t>(index)).object;
  obj.setTransform(fcl::Transform3d(pose.matrix()));
  obj.computeAABB();  // the cached world box is stale after a pose change
}

int RigidContacts::object_count() const { return static_cast<int>(impl_->entries.size()); }

int RigidContacts::query_sphere(const Eigen::Vector3d& centre_m, double radius_m,
                                std::vector<RigidContact>& out) const {
  auto geom = std::make_shared<fcl::Sphered>(radius_m);
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.translation() = centre_m;
  fcl::CollisionObjectd q(geom, tf);
  q.computeAABB();
  return impl_->query(q, out);
}

int RigidContacts::query_box(const Eigen::Vector3d& half_extents_m, const Eigen::Isometry3d& pose,
                             std::vector<RigidContact>& out) const {
  auto geom = std::make_shared<fcl::Boxd>(2.0 * half_extents_m);
  fcl::CollisionObjectd q(geom, fcl::Transform3d(pose.matrix()));
  q.computeAABB();
  return impl_->query(q, out);
}

double RigidContacts::sphere_signed_distance(const Eigen::Vector3d& centre_m, double radius_m,
                                             int index) const {
  auto geom = std::make_shared<fcl::Sphered>(radius_m);
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.translation() = centre_m;
  fcl::CollisionObjectd q(geom, tf);
  q.computeAABB();
  const auto& obj = *impl_->entries.at(static_cast<std::size_t>(index)).object;
  fcl::CollisionRequestd creq(1, true);
  fcl::CollisionResultd cres;
  fcl::collide(&q, &obj, creq, cres);
  if (cres.numContacts() > 0) return -cres.getContact(0).penetration_depth;
  fcl::DistanceRequestd dreq(true);
  fcl::DistanceResultd dres;
  fcl::distance(&q, &obj, dreq, dres);
  return dres.min_distance;
}

}  // namespace teleop::sim::collision
