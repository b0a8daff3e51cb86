#pragma once
// The scene description and mesh topologies the server publishes once, derived from the world
// model (see common/dds/scene_objects.hpp for the conventions observers rely on).
#include <vector>

#include "server/world/world.hpp"
#include "teleop/idl/Teleop.h"

namespace teleop::server {

/// The scene as observers see it: planes, the slave's tip (the robot's own tip sphere in
/// robot scenes, the tool otherwise), each deformable body's bounding sphere at rest, and the
/// robot's frames at q = 0. `physics_rate_hz` is the rate the server actually runs.
SceneDescription describe_scene(const sim::WorldModel& model, const sim::WorldData& data,
                                double physics_rate_hz);

/// The triangles of each deformable body (published once; frames carry positions only).
std::vector<MeshTopology> mesh_topologies(const sim::WorldModel& model);

/// Appends the robot's frames 0..n at q = 0 as OBJECT_ROBOT_LINK objects (ids
/// scene_objects::kRobotFrameIdBase + i) to `scene`. Observers animate them with the joint
/// positions of SlaveState (product of exponentials).
void append_robot_frames(const sim::robot::RobotModel& model, SceneDescription& scene);

}  // namespace teleop::server
