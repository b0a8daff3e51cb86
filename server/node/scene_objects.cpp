#include "server/node/scene_objects.hpp"

#include "common/dds/scene_objects.hpp"
#include "server/robot/kinematics.hpp"

namespace teleop::server {

void append_robot_frames(const sim::robot::RobotModel& model, SceneDescription& scene) {
  sim::robot::Frames frames;
  const sim::robot::JointVector q = sim::robot::JointVector::Zero(model.n);
  sim::robot::forward_kinematics(model, q, frames);
  for (int i = 0; i <= model.n; ++i) {
    SceneObject o;
    o.id(scene_objects::kRobotFrameIdBase + i);
    o.name(i == 0 ? std::string("base") : model.links[static_cast<std::size_t>(i - 1)].name);
    o.kind(OBJECT_ROBOT_LINK);
    const Eigen::Isometry3d& T = frames.T[static_cast<std::size_t>(i)];
    const Eigen::Quaterniond r(T.linear());
    o.position_m() = {T.translation().x(), T.translation().y(), T.translation().z()};
    o.orientation_wxyz() = {r.w(), r.x(), r.y(), r.z()};
    o.mass_kg(i == 0 ? 0.0 : model.links[static_cast<std::size_t>(i - 1)].mass_kg);
    scene.objects().push_back(o);
  }
}

}  // namespace teleop::server
