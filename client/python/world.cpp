// Scenes and the world step for Python: load a scene (its description as a dict, what the
// server publishes on teleop/scene), and step its world off-line (MuJoCo's mj_step from Python):
// set the tip command, step N times without the GIL, read the tip, the contact force and each
// deformable body's nodes as numpy arrays.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <string>
#include <vector>

#include "client/python/bindings.hpp"
#include "common/harness/in_process.hpp"

namespace py = pybind11;

namespace teleop::python {

namespace {

template <std::size_t N>
py::list list_of(const std::array<double, N>& a) {
  py::list l;
  for (double v : a) l.append(v);
  return l;
}

py::object vec3(const Eigen::Vector3d& v) { return array_of(v.data(), 3, 1); }

/// One object of the scene description.
py::dict object_dict(const SceneObject& o) {
  py::dict d;
  d["id"] = o.id();
  d["name"] = o.name().to_string();
  d["kind"] = static_cast<int>(o.kind());
  d["position_m"] = list_of(o.position_m());
  d["orientation_wxyz"] = list_of(o.orientation_wxyz());
  d["size_m"] = list_of(o.size_m());
  d["normal"] = list_of(o.normal());
  d["offset_m"] = o.offset_m();
  d["stiffness_n_per_m"] = o.stiffness_n_per_m();
  d["mass_kg"] = o.mass_kg();
  d["highest_frequency_radps"] = o.highest_frequency_radps();
  d["stable_step_s"] = o.stable_step_s();
  d["substeps"] = o.substeps();
  d["youngs_modulus_pa"] = o.youngs_modulus_pa();
  d["poisson_ratio"] = o.poisson_ratio();
  return d;
}

/// A loaded scene: the immutable world model, shared by the worlds made from it.
struct Scene {
  std::shared_ptr<const harness::SceneModel> model;
  py::dict description;
};

Scene load_scene(const std::string& path) {
  Scene s;
  s.model = harness::load_scene_model(path);
  s.description = scene_description_dict(harness::describe_scene(*s.model));
  return s;
}

/// A world stepped from Python: the server's world (common/harness/in_process.hpp) with one
/// command, its arguments checked here.
class World {
 public:
  explicit World(const Scene& scene) : world_(scene.model) {}

  void set_tip(const Eigen::Vector3d& position_m, const Eigen::Vector3d& velocity_mps,
               bool kinematic) {
    if (!position_m.allFinite() || !velocity_mps.allFinite()) {
      throw py::value_error("tip: position_m and velocity_mps must be finite");
    }
    world_.set_tip(position_m, velocity_mps, kinematic);
  }

  /// Steps `n` times (without the GIL).
  void step(long long n) {
    if (n < 0) throw py::value_error("n = " + std::to_string(n) + " is negative (allowed >= 0)");
    py::gil_scoped_release release;
    world_.step(static_cast<std::uint64_t>(n));
  }

  bool place_tool(const Eigen::Vector3d& position_m) { return world_.place_tool(position_m); }

  SlaveSample out() const { return world_.readout(); }
  double dt_s() const { return world_.dt_s(); }
  std::uint64_t faults() const { return world_.faults(); }
  std::size_t body_count() const { return world_.body_count(); }

  harness::BodyInfo body_info(long long i) const { return world_.body_info(checked(i)); }
  const Eigen::Matrix3Xd& nodes(long long i) const { return world_.nodes(checked(i)); }
  const Eigen::Matrix3Xd& rest_nodes(long long i) const { return world_.rest_nodes(checked(i)); }
  const Eigen::Matrix3Xi& triangles(long long i) const { return world_.triangles(checked(i)); }

 private:
  std::size_t checked(long long i) const {
    if (i < 0 || static_cast<std::size_t>(i) >= world_.body_count()) {
      throw py::value_error("body = " + std::to_string(i) + " is outside the scene's " +
                            std::to_string(world_.body_count()) + " deformable bodies");
    }
    return static_cast<std::size_t>(i);
  }

  harness::World world_;
};

/// A 3 x N matrix as an N x 3 array.
py::object rows_of(const Eigen::Matrix3Xd& m) {
  // column-major 3 x N: each column is a row of the array
  return array_of(m.data(), static_cast<std::size_t>(m.cols()), 3);
}

/// Facts of a deformable body's model.
py::dict body_dict(const harness::BodyInfo& b) {
  py::dict d;
  d["model"] = b.model;
  d["surface_node_count"] = b.surface_node_count;
  d["node_count"] = b.node_count;
  d["triangle_count"] = b.triangle_count;
  d["total_mass_kg"] = b.total_mass_kg;
  d["volume_m3"] = b.volume_m3;
  d["youngs_modulus_pa"] = b.youngs_modulus_pa;
  d["poisson_ratio"] = b.poisson_ratio;
  d["omega_max_rad_per_s"] = b.omega_max_rad_per_s;
  d["stable_step_s"] = b.stable_step_s;
  return d;
}

py::array_t<int> triangles_of(const Eigen::Matrix3Xi& t) {
  py::array_t<int> a({static_cast<py::ssize_t>(t.cols()), py::ssize_t{3}});
  auto r = a.mutable_unchecked<2>();
  for (Eigen::Index j = 0; j < t.cols(); ++j) {
    for (int k = 0; k < 3; ++k) r(j, k) = t(k, j);
  }
  return a;
}

void bind_scene(py::module_& m) {
  py::class_<Scene>(m, "Scene", "A loaded scene file (server/world/world_model.hpp).")
      .def_property_readonly("file", [](const Scene& s) { return harness::scene_file(*s.model); })
      .def_property_readonly("name", [](const Scene& s) { return harness::scene_name(*s.model); })
      .def_property_readonly(
          "physics_rate_hz",
          [](const Scene& s) { return harness::scene_physics_rate_hz(*s.model); })
      .def_readonly("description", &Scene::description,
                    "The scene as the server publishes it (teleop/scene), as a dict.");
  m.def("load_scene", &load_scene, py::arg("path"),
        "Loads and validates a scene file (ValueError naming file, field, value and range).");
}

}  // namespace

py::dict scene_description_dict(const SceneDescription& s) {
  py::dict d;
  d["name"] = s.name().to_string();
  d["gravity_mps2"] = list_of(s.gravity_mps2());
  d["physics_rate_hz"] = s.physics_rate_hz();
  d["visual_rate_hz"] = s.visual_rate_hz();
  d["tip_radius_m"] = s.tip_radius_m();
  d["joint_count"] = s.joint_count();
  d["workspace_min_m"] = list_of(s.workspace_min_m());
  d["workspace_max_m"] = list_of(s.workspace_max_m());
  py::list objects;
  for (const SceneObject& o : s.objects()) objects.append(object_dict(o));
  d["objects"] = objects;
  return d;
}

void bind_world(py::module_& m) {
  bind_scene(m);
  py::class_<World>(m, "World", "A scene's world, stepped off-line (server/world/world.hpp).")
      .def(py::init<const Scene&>(), py::arg("scene"))
      .def("set_tip", &World::set_tip, py::arg("position_m"),
           py::arg("velocity_mps") = Eigen::Vector3d::Zero(), py::arg("kinematic") = false,
           "The command the slave tracks (world frame [m], [m/s]); kinematic: a tool put there.")
      .def("step", &World::step, py::arg("n") = 1, "Advances the world n physics periods.")
      .def("place_tool", &World::place_tool, py::arg("position_m"),
           "Puts the tool at rest there (False for a robot scene).")
      .def_property_readonly("dt_s", &World::dt_s)
      .def_property_readonly("time_s", [](const World& w) { return w.out().sim_time_s; })
      .def_property_readonly("tip_position_m",
                             [](const World& w) { return vec3(w.out().position_m); })
      .def_property_readonly("tip_velocity_mps",
                             [](const World& w) { return vec3(w.out().velocity_mps); })
      .def_property_readonly("contact_force_n",
                             [](const World& w) { return vec3(w.out().contact_force_n); })
      .def_property_readonly("in_contact", [](const World& w) { return w.out().in_contact; })
      .def_property_readonly("penetration_m", [](const World& w) { return w.out().penetration_m; })
      .def_property_readonly("deformation_m", [](const World& w) { return w.out().deformation_m; })
      .def_property_readonly("faults", &World::faults, "Fault events of the world so far.")
      .def_property_readonly("body_count", &World::body_count)
      .def(
          "nodes", [](const World& w, long long body) { return rows_of(w.nodes(body)); },
          py::arg("body") = 0, "Node positions of a deformable body, N x 3 [m].")
      .def(
          "rest_nodes", [](const World& w, long long body) { return rows_of(w.rest_nodes(body)); },
          py::arg("body") = 0, "Rest positions of the same nodes, N x 3 [m].")
      .def(
          "triangles",
          [](const World& w, long long body) { return triangles_of(w.triangles(body)); },
          py::arg("body") = 0, "Surface triangles (node indices), M x 3.")
      .def(
          "body", [](const World& w, long long body) { return body_dict(w.body_info(body)); },
          py::arg("body") = 0, "The deformable body's model: kind, sizes, mass, material.");
}

}  // namespace teleop::python
