// The extension module `teleop._teleop`: what the package `teleop` (teleop/__init__.py) is
// built on. Configuration errors (a bad scene, campaign, parameter or recording) arrive in
// Python as ValueError with the loader's message (file, field, value, allowed range).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <cstring>

#include "client/python/bindings.hpp"
#include "common/config/config.hpp"
#include "common/mesh/tri_mesh.hpp"
#include "common/record/recording.hpp"

namespace py = pybind11;

namespace teleop::python {

py::object array_of(const double* data, std::size_t rows, std::size_t width) {
  py::array_t<double> a =
      width == 1
          ? py::array_t<double>(static_cast<py::ssize_t>(rows))
          : py::array_t<double>({static_cast<py::ssize_t>(rows), static_cast<py::ssize_t>(width)});
  if (rows * width > 0) std::memcpy(a.mutable_data(), data, rows * width * sizeof(double));
  return std::move(a);
}

}  // namespace teleop::python

PYBIND11_MODULE(_teleop, m) {
  m.doc() = "teleop: in-process sessions, campaigns, the world step and recordings";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const teleop::config::ConfigError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const teleop::record::RecordingError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const teleop::mesh::MeshError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });
  teleop::python::bind_sessions(m);
  teleop::python::bind_world(m);
  teleop::python::bind_recording(m);
}
