#pragma once
// The operator model: a human hand, modelled as an impedance (stiffness, damping, mass) that
// tracks an intended trajectory. The intended trajectory comes from a script: hold, line,
// circle, step, or the paper's Fig. 13 task (approach, contact, press, slip, depart).
//
// Every trajectory is an analytic function of time (minimum-jerk segments between
// waypoints), so evaluation allocates nothing and is exactly reproducible.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <string>

namespace teleop::master {

/// Hand impedance coupling the operator's intention to the device handle.
/// Typical values for a relaxed-to-firm grasp: K 100-1000 N/m, B 2-20 N s/m, m 0.2-1 kg.
struct HandImpedance {
  double stiffness_n_per_m = 300.0;  ///< K_h: spring between intended and actual position [N/m]
  double damping_ns_per_m = 6.0;     ///< B_h: damper between intended and actual velocity [N s/m]
  double mass_kg = 0.4;              ///< m_h: hand mass moving with the handle [kg]
};

/// Which intended trajectory the operator follows.
enum class ScriptKind { kHold, kLine, kCircle, kStep, kPressSlip };

/// Parameters of an operator script. All positions in the device frame [m], times [s].
struct OperatorScript {
  ScriptKind kind = ScriptKind::kHold;
  Eigen::Vector3d start_m = Eigen::Vector3d::Zero();  ///< where every script begins [m]

  // line: start -> line_end and back, one leg every `segment_s`, repeated
  Eigen::Vector3d line_end_m = Eigen::Vector3d(0.05, 0.0, 0.0);  ///< [m]

  // circle: around start + circle_center_offset in the plane spanned by circle_axes
  double circle_radius_m = 0.03;                        ///< [m]
  double circle_period_s = 2.0;                         ///< [s]
  Eigen::Vector3d circle_u = Eigen::Vector3d::UnitX();  ///< first in-plane unit axis
  Eigen::Vector3d circle_v = Eigen::Vector3d::UnitY();  ///< second in-plane unit axis

  // step: start until step_time_s, then start + step_m (instantaneous intention)
  Eigen::Vector3d step_m = Eigen::Vector3d(0.0, 0.0, -0.02);  ///< step size [m]
  double step_time_s = 0.5;                                   ///< [s]

  // press-slip (Fig. 13): approach the sphere's top, press `press_depth_m` below the
  // surface, slip sideways by `slip_m`, depart back up to `approach_height_m` above the top.
  Eigen::Vector3d sphere_top_m = Eigen::Vector3d(0.0, 0.0, 0.0);  ///< top of sphere [m]
  double press_depth_m = 0.02;      ///< intended depth below the surface [m]
  double approach_height_m = 0.05;  ///< start/end height above the top [m]
  Eigen::Vector3d slip_m = Eigen::Vector3d(0.03, 0.0, 0.0);  ///< sideways slip while pressing [m]

  double segment_s = 1.0;  ///< duration of each minimum-jerk segment (line, press-slip) [s]
  double dwell_s = 0.5;    ///< pause at each press-slip waypoint [s]
  bool repeat = false;     ///< press-slip / line restart at the end instead of holding

  /// Physiological tremor added to every script: per axis, a sum of three sinusoids
  /// (4.1, 7.3, 10.7 Hz, axis-dependent phases), each of this amplitude [m]. It excites the
  /// loop's resonances as a real hand does (typical 0.05-0.2 mm); 0 disables it.
  double tremor_amplitude_m = 0.0;
};

/// Parses "hold" | "line" | "circle" | "step" | "press-slip". @throws config::ConfigError.
ScriptKind parse_script_kind(const std::string& name);
/// Name of a script kind (inverse of parse_script_kind).
const char* script_kind_name(ScriptKind kind);

/// Builds the press-slip script for a sphere whose top point is `top_m` (device frame).
OperatorScript press_slip_script(const Eigen::Vector3d& top_m, double press_depth_m);

/// Intended hand pose at one instant.
struct IntendedPose {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();    ///< [m]
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();  ///< [m/s]
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d angular_velocity_radps = Eigen::Vector3d::Zero();  ///< [rad/s]
  int phase = 0;  ///< script phase index (press-slip: 0 approach ... 4 depart, 5 done)
};

/// Evaluates the script at time t [s]. Pure, allocation-free.
IntendedPose intended_pose(const OperatorScript& script, double t_s);

/// Total duration of one pass of the script [s] (hold/circle/step: 0 = unbounded).
double script_duration_s(const OperatorScript& script);

/// Force the hand applies to the handle [N]: K_h (x_d - x) + B_h (v_d - v).
inline Eigen::Vector3d hand_force(const HandImpedance& hand, const IntendedPose& want,
                                  const Eigen::Vector3d& x_m, const Eigen::Vector3d& v_mps) {
  return hand.stiffness_n_per_m * (want.position_m - x_m) +
         hand.damping_ns_per_m * (want.velocity_mps - v_mps);
}

}  // namespace teleop::master
