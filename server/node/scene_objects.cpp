#include "server/node/scene_objects.hpp"

#include <cmath>

#include "common/dds/scene_objects.hpp"
#include "common/util/version.hpp"
#include "server/robot/kinematics.hpp"

namespace teleop::server {

namespace {
template <std::size_t N>
void copy3(std::array<double, N>& dst, const Eigen::Vector3d& v) {
  dst[0] = v.x();
  dst[1] = v.y();
  dst[2] = v.z();
}
}  // namespace

SceneDescription describe_scene(const sim::WorldModel& model, const sim::WorldData& data,
                                double physics_rate_hz) {
  SceneDescription d;
  d.name(model.name);
  d.build_version(version_string());
  copy3(d.gravity_mps2(), model.gravity_mps2);
  d.physics_rate_hz(physics_rate_hz);
  d.visual_rate_hz(model.visual_rate_hz);
  d.tip_radius_m(model.tip_radius_m());
  d.joint_count(static_cast<std::uint32_t>(data.out.joint_count));
  copy3(d.workspace_min_m(), model.workspace_min_m);
  copy3(d.workspace_max_m(), model.workspace_max_m);
  for (const auto& p : model.planes) {
    SceneObject o;
    o.id(p.id);
    o.name(p.name);
    o.kind(OBJECT_PLANE);
    copy3(o.normal(), p.normal);
    o.offset_m(p.offset_m);
    o.stiffness_n_per_m(p.stiffness_n_per_m);
    d.objects().push_back(o);
  }
  SceneObject tip;
  tip.id(1);
  tip.name(model.has_robot() ? "tip" : "tool");
  tip.kind(OBJECT_TOOL);
  tip.size_m()[0] = model.tip_radius_m();
  tip.mass_kg(model.tip_mass_kg());
  d.objects().push_back(tip);
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    const Eigen::Matrix3Xd& x = data.bodies[i].state.x;
    SceneObject o;
    o.id(model.bodies[i].object_id);
    o.name("deformable" + std::to_string(i));
    o.kind(OBJECT_DEFORMABLE_MESH);
    // bounding sphere at load: centroid and largest node distance; the height of its highest
    // node above that centroid (where a tip coming from above touches it)
    const Eigen::Vector3d centre = x.rowwise().mean();
    copy3(o.position_m(), centre);
    o.size_m()[0] = (x.colwise() - centre).colwise().norm().maxCoeff();
    o.size_m()[1] = x.row(2).maxCoeff() - centre.z();
    // the automatic step: what the body's highest mode allows, and what it takes per step
    const sim::deformable::DeformableModel& m = model.bodies[i].body;
    o.highest_frequency_radps(m.omega_max_rad_per_s);
    o.stable_step_s(std::isfinite(m.stable_step_s) ? m.stable_step_s : -1.0);
    o.substeps(static_cast<std::uint32_t>(m.substeps_for(1.0 / physics_rate_hz)));
    // what the tip meets (measured at load for fem), the body's weight and its material
    o.stiffness_n_per_m(data.bodies[i].contact_stiffness_n_per_m);
    o.mass_kg(m.total_mass_kg);
    o.youngs_modulus_pa(m.params.youngs_modulus_pa);
    o.poisson_ratio(m.params.poisson_ratio);
    d.objects().push_back(o);
  }
  // the robot's frames at q = 0, so observers can draw the arm from the joint positions
  if (model.has_robot()) append_robot_frames(*model.robot, d);
  return d;
}

std::vector<MeshTopology> mesh_topologies(const sim::WorldModel& model) {
  std::vector<MeshTopology> out;
  for (const sim::DeformableBodyModel& b : model.bodies) {
    const Eigen::Matrix3Xi& tris = b.body.mesh.triangles;
    MeshTopology t;
    t.object_id(b.object_id);
    t.vertex_count(static_cast<std::uint32_t>(b.body.mesh.vertices.cols()));
    auto& idx = t.triangle_indices();
    idx.reserve(static_cast<std::size_t>(tris.size()));
    for (Eigen::Index c = 0; c < tris.cols(); ++c) {
      for (int r = 0; r < 3; ++r) idx.push_back(static_cast<std::uint32_t>(tris(r, c)));
    }
    out.push_back(std::move(t));
  }
  return out;
}

void append_robot_frames(const sim::robot::RobotModel& model, SceneDescription& scene) {
  sim::robot::Frames frames;
  const sim::robot::JointVector q = sim::robot::JointVector::Zero(model.n);
  sim::robot::forward_kinematics(model, q, frames);
  for (int i = 0; i <= model.n; ++i) {
    SceneObject o;
    o.id(scene_objects::kRobotFrameIdBase + i);
    o.name(i == 0 ? std::string("base") : model.links[static_cast<std::size_t>(i - 1)].name);
    o.kind(OBJECT_ROBOT_LINK);
    const Eigen::Isometry3d& T = frames.T[static_cast<std::size_t>(i)];
    const Eigen::Quaterniond r(T.linear());
    o.position_m() = {T.translation().x(), T.translation().y(), T.translation().z()};
    o.orientation_wxyz() = {r.w(), r.x(), r.y(), r.z()};
    o.mass_kg(i == 0 ? 0.0 : model.links[static_cast<std::size_t>(i - 1)].mass_kg);
    scene.objects().push_back(o);
  }
}

}  // namespace teleop::server
