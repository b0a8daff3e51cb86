#pragma once
// Conventions for SceneDescription.objects (idl/Teleop.idl), shared by the server that writes
// them and the observers that read them.
//
// Ids: the tool/tip is 1, deformable bodies 10-99 (scene file), planes 100 + their index in the
// scene file, robot frames kRobotFrameIdBase + i.
//
// Robot frames (robot scenes only): joint_count + 1 objects of kind OBJECT_ROBOT_LINK, ids
// kRobotFrameIdBase + i for i = 0..joint_count. Object i carries the world pose (position_m,
// orientation_wxyz) of the chain's frame i with every joint at zero (q = 0): frame 0 is the
// base, frame i (i >= 1) is attached to link i, and joint i + 1 turns about the z axis of frame
// i through its origin (standard Denavit-Hartenberg). mass_kg is link i's mass (0 for the base);
// size_m is unused (zero). From these and SlaveState.joint_position_rad an observer gets every
// frame at any q by the product of exponentials:
//   T_i(q) = R_1(q_1) ... R_i(q_i) T_i(0),
// R_j(a) = rotation by a [rad] about the z axis of T_{j-1}(0), through its origin.
namespace teleop::scene_objects {

/// Id of robot frame i (0 = base) in SceneDescription.objects.
inline constexpr int kRobotFrameIdBase = 200;

}  // namespace teleop::scene_objects
