#pragma once
// The simulated world as the server node sees it: one step per physics period, a command in,
// the slave tip's state out. Implementations: ToolWorld (tool-only scene); the robot and
// deformable scene assemble robot, planes, deformable bodies and contact.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <memory>

#include "server/world/events.hpp"
#include "server/world/scene.hpp"

namespace teleop::sim {

constexpr int kMaxJoints = 8;

/// One validated command, in the slave (world) frame.
struct WorldCommand {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_velocity_radps = Eigen::Vector3d::Zero();
  double kp_override_n_per_m = 0.0;  ///< >0 overrides the slave's position gain [N/m]
  bool hold = false;                 ///< hold the current pose (watchdog, clutch)
};

/// State of the slave after a step.
struct WorldOutput {
  Eigen::Vector3d tip_position_m = Eigen::Vector3d::Zero();
  Eigen::Quaterniond tip_orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d tip_velocity_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d tip_angular_velocity_radps = Eigen::Vector3d::Zero();
  Eigen::Vector3d contact_force_n = Eigen::Vector3d::Zero();  ///< environment force on the tip
  Eigen::Vector3d contact_torque_nm = Eigen::Vector3d::Zero();
  double penetration_m = 0.0;  ///< contact spring compression x of F = k x [m]
  double deformation_m = 0.0;  ///< indentation of a deformable body since contact began [m]
  bool in_contact = false;
  int contact_object = -1;
  /// Force of the slave's tracking controller on the tip this step [N] (tool: its PD, without
  /// gravity compensation; robot: estimated as -contact_force_n, the quasi-static balance).
  Eigen::Vector3d tracking_force_n = Eigen::Vector3d::Zero();
  double tracking_kp_n_per_m = 400.0;  ///< the tracking law's default stiffness [N/m]
  double tracking_kd_ns_per_m = 12.0;  ///< its damping [N s/m]
  int joint_count = 0;
  std::array<double, kMaxJoints> q_rad{}, qd_radps{}, tau_nm{};
  double sim_time_s = 0.0;
};

/// A deformable surface for publishing (topology once, positions at the visual rate).
struct DeformableView {
  int object_id = -1;
  const Eigen::Matrix3Xi* triangles = nullptr;
  const Eigen::Matrix3Xd* positions = nullptr;
};

class World {
 public:
  virtual ~World() = default;
  /// Advances by dt [s]. Allocation-free. Faults are pushed into `events` and handled.
  virtual void step(const WorldCommand& cmd, double dt_s, EventQueue& events) = 0;
  virtual const WorldOutput& output() const = 0;
  /// Deformable bodies to publish (empty for rigid-only scenes).
  virtual int deformable_count() const { return 0; }
  virtual DeformableView deformable(int /*index*/) const { return {}; }
};

/// The tool scene's input for a world command.
ToolInput to_tool_input(const WorldCommand& cmd);

/// Builds the world for a scene. @throws config::ConfigError for an invalid scene.
std::unique_ptr<World> make_world(const SceneConfig& scene);

/// The tool-only scene as a World.
class ToolWorld : public World {
 public:
  explicit ToolWorld(const SceneConfig& scene);
  void step(const WorldCommand& cmd, double dt_s, EventQueue& events) override;
  const WorldOutput& output() const override { return out_; }
  const ToolState& tool_state() const { return state_; }

 private:
  ToolModel model_;
  ToolState state_;
  WorldOutput out_;
  bool was_in_contact_ = false;
};

}  // namespace teleop::sim
