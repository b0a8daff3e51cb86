#pragma once
// The plain fields of a deformable body's `body:` mapping, each declared once
// (common/config/field_table.hpp): key, unit, help, range, and the DeformableParams field whose
// member initialiser is the default. load_deformable_params (params.cpp) reads them with this
// table; the fields whose default or meaning depends on the model (model, integrator, kernel,
// level, the mesh files, density, the radial springs, the Rayleigh damping, nodal_pressure) are
// read by its own code. docs/configuration.md's table of them is part of
// `teleop_server --print-scene-parameters` (server/world/scene_params.hpp).
#include <vector>

#include "common/config/field_table.hpp"
#include "server/deformable/deformable.hpp"

namespace teleop::sim::deformable {

/// The table (see the file comment), in the order the docs list it.
const std::vector<config::FieldParam<DeformableParams>>& body_field_params();

}  // namespace teleop::sim::deformable
