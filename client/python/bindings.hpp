#pragma once
// The parts of the Python module `teleop._teleop` (module.cpp): in-process sessions and
// campaign runs (sessions.cpp), scenes and the world step (world.cpp), recordings
// (recording.cpp). Each adds its functions and classes to the module.
#include <pybind11/pybind11.h>

#include <cstddef>
#include <vector>

namespace teleop {
class SceneDescription;
}

namespace teleop::python {

void bind_sessions(pybind11::module_& m);
void bind_world(pybind11::module_& m);
void bind_recording(pybind11::module_& m);

/// The scene description (the teleop/scene sample) as a dict.
pybind11::dict scene_description_dict(const SceneDescription& s);

/// A new float64 array of `rows` x `width` (1-D when width is 1) copied from `data` (row-major).
pybind11::object array_of(const double* data, std::size_t rows, std::size_t width);

}  // namespace teleop::python
