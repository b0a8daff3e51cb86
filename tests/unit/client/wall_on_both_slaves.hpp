#pragma once
// A wall at z = 0.5 m seen by both slaves the master side runs against: the in-process
// PointSlave and the server's tool scene, with the same stiffness and damping, so tests can
// drive them with the same commands and require the same motion.
#include "client/control/slave_model.hpp"
#include "server/world/tool_scene.hpp"

namespace teleop::test {

struct WallOnBothSlaves {
  using PointSlaveParams = teleop::master::PointSlaveParams;
  using SlaveObstacle = teleop::master::SlaveObstacle;

  PointSlaveParams point;       ///< build a PointSlave from it
  teleop::sim::ToolModel tool;  ///< the server's tool scene with the same plane

  WallOnBothSlaves() {
    SlaveObstacle wall;
    wall.kind = SlaveObstacle::Kind::kPlane;
    wall.offset_m = 0.5;
    point.add(wall);
    tool.plane_count = 1;
    tool.planes[0].id = 0;
    tool.planes[0].offset_m = wall.offset_m;
    tool.planes[0].stiffness_n_per_m = wall.stiffness_n_per_m;
    tool.planes[0].damping_ns_per_m = wall.damping_ns_per_m;
  }
};

}  // namespace teleop::test
