#pragma once
// An in-process slave for tests and the delay-robustness sweep (no DDS, no teleop::sim
// library): the tool law of common/sim/tool.hpp (the same law as the server's tool slave, with
// planes and spheres as obstacles) behind the slave side of the passivity schemes
// (common/control/slave_port.hpp), exactly as the server runs it:
//   target = port.before_step(cmd); tool_step(model, state, target); port.after_step(f_pd).
// step() allocates nothing.
#include "common/control/bilateral_types.hpp"
#include "common/control/contact_model.hpp"
#include "common/control/slave_port.hpp"
#include "common/sim/tool.hpp"

namespace teleop::master {

/// The point slave's parameters are the tool law's model.
using PointSlaveParams = sim::ToolModel;
using SlaveObstacle = sim::Obstacle;

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

/// The tool law as an in-process slave.
class PointSlave final : public SlaveSimulator {
 public:
  explicit PointSlave(const PointSlaveParams& params) : params_(params) {}
  void reset(const Eigen::Vector3d& position_m) override;
  void step(const SlaveCommand& command, double dt_s) override;
  SlaveSample sample() const override { return sample_; }
  const PointSlaveParams& params() const { return params_; }
  PointSlaveParams& params() { return params_; }
  /// The slave side of the passivity schemes.
  const passivity::SlavePassivityPort& port() const { return port_; }
  /// PD tracking force of the last step [N].
  const Eigen::Vector3d& tracking_force_n() const { return state_.tracking_force_n; }

 private:
  /// The nearest obstacle surface to the tip (the model-mediated scheme's prior).
  mmt::SurfacePrior nearest_surface(const Eigen::Vector3d& tip_m) const;

  PointSlaveParams params_;
  sim::ToolState state_;
  SlaveSample sample_;
  passivity::SlavePassivityPort port_;
  mmt::ContactEstimator estimator_;
};

}  // namespace teleop::master
