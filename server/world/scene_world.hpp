#pragma once
// The assembled scene: a slave (the 6-DoF robot in ODE, or the free tool), the rigid planes,
// and any number of deformable bodies, with tip-mesh contact between the slave's tip and each
// body. One step (dt):
//   1. each body's f_ext is cleared; the tip-mesh contact of each body is updated along the
//      tip's path of the last step (eq. 8 / continuous detection), giving the force on the tip
//      and adding the equal and opposite reaction onto the body's nodes;
//   2. each body steps (mass-spring or Navier, nodes against the planes);
//   3. the slave steps with the summed deformable contact force as an external tip force
//      (robot: tau = J^T gamma, eq. 4), the planes acting on the tip and links in ODE;
//   4. outputs: tip state, total environment force on the tip (planes + bodies), penetration.
// Allocation-free after construction; deterministic for the same inputs.
#include <memory>
#include <vector>

#include "server/collision/tip_mesh_contact.hpp"
#include "server/deformable/deformable.hpp"
#include "server/robot/robot_sim.hpp"
#include "server/world/world.hpp"

namespace teleop::sim {

/// One deformable body of a scene with its contact law.
struct DeformableEntry {
  int object_id = 10;
  deformable::DeformableModel model;
  deformable::DeformableState state;
  collision::TipMeshContact contact;
  collision::TipContactResult last;
};

/// Reads the `deformables[i]` mapping: {id, body: <deformable params>, contact: {...}}.
/// @throws config::ConfigError.
collision::TipContactParams load_tip_contact_params(const config::Node& node);

class SceneWorld : public World {
 public:
  /// Builds robot (when scene.kind == "robot") or tool, and the deformable bodies.
  /// @throws config::ConfigError for an invalid scene.
  explicit SceneWorld(const SceneConfig& scene);
  ~SceneWorld() override;

  void step(const WorldCommand& cmd, double dt_s, EventQueue& events) override;
  const WorldOutput& output() const override { return out_; }
  int deformable_count() const override { return static_cast<int>(bodies_.size()); }
  DeformableView deformable(int index) const override;

  bool has_robot() const { return robot_ != nullptr; }
  const robot::RobotSim* robot() const { return robot_.get(); }
  const DeformableEntry& body(int i) const { return *bodies_[static_cast<std::size_t>(i)]; }
  DeformableEntry& body(int i) { return *bodies_[static_cast<std::size_t>(i)]; }
  /// Force on the tip from the deformable bodies in the last step [N].
  const Eigen::Vector3d& deformable_force_n() const { return deformable_force_; }

 private:
  void read_outputs();

  SceneConfig scene_;
  std::unique_ptr<robot::RobotSim> robot_;
  Eigen::Quaterniond home_orientation_ = Eigen::Quaterniond::Identity();
  ToolModel tool_model_;
  ToolState tool_state_;
  std::vector<std::unique_ptr<DeformableEntry>> bodies_;
  Eigen::Vector3d tip_prev_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d deformable_force_ = Eigen::Vector3d::Zero();
  double tip_radius_m_ = 0.05;
  WorldOutput out_;
  bool was_in_contact_ = false;
};

}  // namespace teleop::sim
