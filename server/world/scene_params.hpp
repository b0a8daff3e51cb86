#pragma once
// The plain fields of a scene file, each declared once (common/config/field_table.hpp): the
// world box, physics, command, tool, each plane's, and each deformable body's tip contact (the
// body's own: server/deformable/body_params.hpp). The
// scene loader (server/world/world_model.cpp) reads these mappings with the tables,
// teleop_server's --rate and --command-timeout take their ranges from them, and
// docs/configuration.md's table of them is `teleop_server --print-scene-parameters`
// (ctest docs.scene_parameters_table_is_the_programs). The fields with rules beyond a range (a
// plane's name and normal, a body's model and the fields whose default depends on it, the robot)
// are read by the loader's own code and described by hand in the docs.
#include <string>
#include <vector>

#include "common/config/field_table.hpp"
#include "common/sim/plane.hpp"
#include "server/collision/tip_mesh_contact.hpp"

namespace teleop::sim {

struct WorldModel;

/// `world:` (the world box).
const std::vector<config::FieldParam<WorldModel>>& world_box_params();
/// `physics:`.
const std::vector<config::FieldParam<WorldModel>>& physics_params();
/// `command:`.
const std::vector<config::FieldParam<WorldModel>>& command_params();
/// `tool:` (the free tool and the start of the tool slave).
const std::vector<config::FieldParam<WorldModel>>& tool_params();
/// Each entry of `planes:` (besides `name` and `normal`).
const std::vector<config::FieldParam<Plane>>& plane_params();
/// `contact:` of each entry of `deformables:` (the tip against the body's surface).
const std::vector<config::FieldParam<collision::TipContactParams>>& tip_contact_params();

/// The entry `key` of `table`. @throws std::out_of_range when there is none.
template <class S>
const config::FieldParam<S>& scene_param(const std::vector<config::FieldParam<S>>& table,
                                         const std::string& key);

/// The tables as one markdown table (field, unit, default, range, help), ending with a newline:
/// what `teleop_server --print-scene-parameters` prints and docs/configuration.md holds between
/// `<!-- scene-parameters -->` and `<!-- /scene-parameters -->`.
std::string scene_params_markdown();

}  // namespace teleop::sim
