#pragma once
// Scene-description objects the server derives from its models (see
// common/dds/scene_objects.hpp for the conventions observers rely on).
#include "server/robot/robot_model.hpp"
#include "teleop/idl/Teleop.h"

namespace teleop::server {

/// Appends the robot's frames 0..n at q = 0 as OBJECT_ROBOT_LINK objects (ids
/// scene_objects::kRobotFrameIdBase + i) to `scene`. Observers animate them with the joint
/// positions of SlaveState (product of exponentials).
void append_robot_frames(const sim::robot::RobotModel& model, SceneDescription& scene);

}  // namespace teleop::server
