#pragma once
// An in-process slave for tests and the delay-robustness sweep (no DDS, no teleop::sim):
// a point tool of mass m_s and viscous damping b_s, tracking the command with a PD (K_ps,
// B_ps, velocity feed-forward), saturated, in contact with penalty environments:
//   - planes (a stiff wall/floor):   f = max(0, k d - b v_n) n,  d = penetration [m]
//   - spheres (the deformable ball as a soft linear spring around its surface): same law
//     with n the outward normal at the contact and d = R + r_tool - |x - c|.
// It is the same law as the server's tool-only scene (common/sim/tool.hpp), with
// spheres added; a test checks the two agree on a plane. step() allocates nothing.
//
// The passivity schemes (wave variables, TDPA) run their slave side through the same
// teleop::passivity::SlavePassivityPort the server uses (common/control/slave_port.hpp):
// the command goes through the port before the step, the PD force is recorded after it.
#include <array>

#include "common/control/bilateral_types.hpp"
#include "common/control/slave_port.hpp"

namespace teleop::master {

/// A contact primitive of the point slave's environment.
struct SlaveObstacle {
  enum class Kind : std::uint8_t { kPlane, kSphere } kind = Kind::kPlane;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();   ///< plane: unit normal into free space
  double offset_m = 0.0;                               ///< plane: normal . x = offset [m]
  Eigen::Vector3d centre_m = Eigen::Vector3d::Zero();  ///< sphere: centre [m]
  double radius_m = 0.25;                              ///< sphere: radius [m]
  double stiffness_n_per_m = 2.0e4;                    ///< k [N/m]
  double damping_ns_per_m = 50.0;                      ///< b (compression only) [N s/m]
  int id = 0;                                          ///< object id reported on contact
};

/// Parameters of the point slave.
struct PointSlaveParams {
  double mass_kg = 0.2;                  ///< m_s [kg]
  double radius_m = 0.05;                ///< tool sphere radius [m]
  double kp_n_per_m = 400.0;             ///< default K_ps [N/m] (a command may override)
  double kd_ns_per_m = 12.0;             ///< B_ps [N s/m]
  double linear_damping_ns_per_m = 0.5;  ///< b_s, viscous damping to the world [N s/m]
  double max_force_n = 200.0;            ///< PD saturation [N]
  static constexpr int kMaxObstacles = 8;
  std::array<SlaveObstacle, kMaxObstacles> obstacles{};
  int obstacle_count = 0;

  /// Appends an obstacle (at most kMaxObstacles). Returns false if full.
  bool add(const SlaveObstacle& o);
};

/// The passivity fields of a command as the slave port reads them.
passivity::SlavePortCommand port_command(const SlaveCommand& c);
/// Copies the slave port's report into the sample's passivity fields.
void apply_port_report(const passivity::SlavePortReport& r, SlaveSample& s);

/// A slave simulated in-process (interface so other slave models can be plugged in).
class SlaveSimulator {
 public:
  virtual ~SlaveSimulator() = default;
  /// Puts the tool at rest at `position_m` [m], time zero.
  virtual void reset(const Eigen::Vector3d& position_m) = 0;
  /// Advances by dt [s] towards `command` (the newest command received; hold if disabled).
  virtual void step(const SlaveCommand& command, double dt_s) = 0;
  /// The state to send back to the master.
  virtual SlaveSample sample() const = 0;
};

/// The point slave described in the file comment.
class PointSlave final : public SlaveSimulator {
 public:
  explicit PointSlave(const PointSlaveParams& params) : params_(params) {}
  void reset(const Eigen::Vector3d& position_m) override;
  void step(const SlaveCommand& command, double dt_s) override;
  SlaveSample sample() const override { return sample_; }
  /// Parameters in use.
  const PointSlaveParams& params() const { return params_; }
  /// Mutable parameters (between runs).
  PointSlaveParams& params() { return params_; }
  /// The slave side of the passivity schemes.
  const passivity::SlavePassivityPort& port() const { return port_; }
  /// PD tracking force of the last step [N].
  const Eigen::Vector3d& tracking_force_n() const { return f_ctrl_; }

 private:
  PointSlaveParams params_;
  SlaveSample sample_;
  passivity::SlavePassivityPort port_;
  Eigen::Vector3d hold_m_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d f_ctrl_ = Eigen::Vector3d::Zero();
  bool holding_ = false;
};

}  // namespace teleop::master
