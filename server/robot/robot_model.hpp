#pragma once
// The virtual slave robot's immutable model (paper, "Virtual slave model"): an open chain of
// up to kMaxJoints revolute joints described by standard Denavit-Hartenberg parameters, each
// link a rigid box with real inertial parameters, joint limits, viscous + Coulomb friction and
// joint PD gains (K_ps of the paper's Fig. 10), ending in a spherical tip.
//
// The model never changes during a run. It is loaded from the `robot:` mapping of a scene
// file with full validation (load_robot_model); every mistake names file, field, value, range.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string>

#include "common/config/config.hpp"

namespace teleop::sim::robot {

/// Largest number of joints a chain may have (sizes every fixed-capacity Eigen type).
constexpr int kMaxJoints = 6;

/// Joint-space vector (q [rad], qd [rad/s], tau [N m]); size n <= kMaxJoints, never allocates.
using JointVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxJoints, 1>;
/// Geometric Jacobian, 6 x n: rows 0-2 linear velocity [m/s per rad/s], rows 3-5 angular.
using Jacobian = Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, kMaxJoints>;
/// Square joint-space matrix, n x n (n <= kMaxJoints), allocation-free.
using JointMatrix =
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxJoints, kMaxJoints>;
/// Twist [v; w] ([m/s]; [rad/s]) or wrench [f; m] ([N]; [N m]).
using Vector6d = Eigen::Matrix<double, 6, 1>;

/// Standard (distal) Denavit-Hartenberg parameters of one joint/link:
/// T_{i-1,i} = Rz(q_i + theta_offset) Tz(d) Tx(a) Rx(alpha).
struct DhParams {
  double a_m = 0.0;               ///< link length along x_i [m]
  double alpha_rad = 0.0;         ///< link twist about x_i [rad]
  double d_m = 0.0;               ///< link offset along z_{i-1} [m]
  double theta_offset_rad = 0.0;  ///< constant added to q_i [rad]
};

/// One link i and the joint i that moves it (joint i turns about z_{i-1}).
struct LinkModel {
  std::string name;
  DhParams dh;
  double mass_kg = 1.0;                                          ///< link mass [kg]
  Eigen::Vector3d com_m = Eigen::Vector3d::Zero();               ///< centre of mass in frame i [m]
  Eigen::Matrix3d inertia_kgm2 = Eigen::Matrix3d::Identity();    ///< about the COM, frame-i axes
  Eigen::Vector3d box_size_m = Eigen::Vector3d::Constant(0.05);  ///< full box extents [m]
  Eigen::Vector3d box_center_m = Eigen::Vector3d::Zero();        ///< box centre in frame i [m]
  std::string mesh_file;  ///< optional visual mesh (assimp); empty when none
  // joint i
  double q_min_rad = -3.0;           ///< lower joint limit [rad]
  double q_max_rad = 3.0;            ///< upper joint limit [rad]
  double qd_max_radps = 3.0;         ///< joint speed limit of the reference [rad/s]
  double torque_limit_nm = 100.0;    ///< actuator torque saturation [N m]
  double viscous_nms_per_rad = 0.0;  ///< viscous friction b, tau_f = -b qd [N m s/rad]
  double coulomb_nm = 0.0;           ///< Coulomb friction level [N m]
  double kp_nm_per_rad = 100.0;      ///< joint PD stiffness (K_ps, Fig. 10) [N m/rad]
  double kd_nms_per_rad = 10.0;      ///< joint PD damping [N m s/rad]
};

/// Largest share of a joint's torque limit its friction compensation may take at the joint's
/// speed limit (load_robot_model refuses more).
constexpr double kMaxFrictionShare = 0.5;

/// Smallest IK gain a scene may give [1/s]: at 0 the task error is never fed back and the robot
/// does not follow its commands (an inert slave); at 1 /s it follows with a 1 s time constant.
constexpr double kMinIkGainPerS = 1.0;

/// Parameters of the damped-least-squares inverse kinematics that turns a commanded tip pose
/// into a joint reference (resolved-rate with variable damping near singularities).
struct IkParams {
  double gain_per_s = 40.0;                  ///< task-space error feedback gain [1/s]
  double orientation_weight_m = 0.2;         ///< length that weights angular rows vs linear [m]
  double damping_max_m = 0.08;               ///< largest DLS damping lambda [m]
  double singular_threshold_m = 0.04;        ///< damping starts below this sigma_min [m]
  double limit_margin_rad = 0.02;            ///< reference stays this far inside joint limits
  double max_tip_speed_mps = 1.5;            ///< clamp of the commanded tip speed [m/s]
  double max_tip_angular_speed_radps = 4.0;  ///< clamp of the commanded angular speed [rad/s]
  double friction_compensation = 1.0;        ///< fraction of model friction fed forward [0, 1]
  double friction_velocity_radps = 0.02;     ///< smoothing speed of the Coulomb feed-forward
};

/// The immutable robot model.
struct RobotModel {
  std::string name;    ///< e.g. "puma560"
  std::string source;  ///< citation of the parameter source
  int n = 0;           ///< number of joints (1..kMaxJoints)
  std::array<LinkModel, kMaxJoints> links{};
  Eigen::Isometry3d base = Eigen::Isometry3d::Identity();   ///< frame 0 in the world
  Eigen::Vector3d tool_offset_m = Eigen::Vector3d::Zero();  ///< tip centre in frame n [m]
  double tip_radius_m = 0.05;                               ///< spherical tip radius [m]
  double tip_mass_kg = 0.0;  ///< tip sphere mass, already folded into links[n-1] [kg]
  Eigen::Vector3d gravity_mps2 = Eigen::Vector3d(0.0, 0.0, -9.81);  ///< [m/s^2]
  IkParams ik;
  JointVector q_home;  ///< home configuration [rad]

  /// Midpoint of joint i's limits [rad].
  double q_mid(int i) const { return 0.5 * (links[i].q_min_rad + links[i].q_max_rad); }
};

/// Loads and validates the `robot:` mapping of a scene file (see deploy/scenes/robot_*.yaml
/// and docs/robot.md for the fields). Folds the tip mass into the last link. Loads optional
/// link meshes with assimp: a mesh without an explicit box sets the box to the mesh's
/// bounding box (the inertia always comes from the data).
/// @throws teleop::config::ConfigError naming file, field, value and allowed range.
RobotModel load_robot_model(const teleop::config::Node& robot_node);

/// Loads `file`, then its `robot:` mapping. @throws teleop::config::ConfigError.
RobotModel load_robot_model_file(const std::string& file);

/// Path of the default scene fragment (deploy/scenes/robot_puma560.yaml in the source tree).
std::string default_robot_scene_path();

/// Combines two rigid masses given in the same frame: returns the total mass, COM and inertia
/// about the new COM (parallel-axis theorem). Used to fold the tip sphere into the last link.
void combine_masses(double m1_kg, const Eigen::Vector3d& c1_m, const Eigen::Matrix3d& i1_kgm2,
                    double m2_kg, const Eigen::Vector3d& c2_m, const Eigen::Matrix3d& i2_kgm2,
                    double& m_kg, Eigen::Vector3d& c_m, Eigen::Matrix3d& i_kgm2);

}  // namespace teleop::sim::robot
