#pragma once
// The fields of a robot's `ik:` mapping, each declared once (common/config/field_table.hpp):
// load_robot_model reads them with this table, and docs/configuration.md's table of them is
// part of `teleop_server --print-scene-parameters` (server/world/scene_params.hpp).
#include <vector>

#include "common/config/field_table.hpp"
#include "server/robot/robot_model.hpp"

namespace teleop::sim::robot {

/// The table, in the order the docs list it.
const std::vector<config::FieldParam<IkParams>>& ik_field_params();

}  // namespace teleop::sim::robot
