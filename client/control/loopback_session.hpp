#pragma once
// LoopbackSession: the whole bilateral loop in one process, without DDS, at a fixed period:
//
//   device.read -> backward.pop_newest -> controller.update -> safety.filter -> device.write
//   -> forward.push(command) ... forward.pop_newest -> slave.step -> backward.push(sample)
//   -> metrics.update -> device.advance(dt)
//
// It is what the master node does each haptic cycle (with DDS in place of the in-process
// slave), and what the delay-robustness sweep and the tests run. step() allocates nothing.
#include <memory>

#include "client/control/bilateral_controller.hpp"
#include "client/control/slave_model.hpp"
#include "client/device/haptic_device.hpp"
#include "client/metrics/safety.hpp"
#include "client/metrics/session_metrics.hpp"
#include "client/net/delay_channel.hpp"

namespace teleop::master {

/// Everything a loopback run needs besides the device and the slave.
struct LoopbackConfig {
  ControllerParams controller;  ///< scheme, gains, workspace map
  DelayConfig forward;          ///< master -> slave impairment
  DelayConfig backward;         ///< slave -> master impairment
  SafetyParams safety;          ///< safety layer thresholds
  bool safety_enabled = true;   ///< false: the controller's force goes straight to the device
  VerdictParams verdict;        ///< verdict thresholds
  double dt_s = 1e-3;           ///< haptic and slave period [s]
  double duration_s = 5.0;      ///< run() length [s]
};

/// The in-process loop. See the file comment.
class LoopbackSession {
 public:
  /// Allocates channels and the controller. @throws ConfigError on bad configuration.
  LoopbackSession(const LoopbackConfig& cfg, HapticDevice& device, SlaveSimulator& slave);

  /// Configures and activates device and controller; puts the slave at the mapped device
  /// position. Call once before step().
  void start();
  /// One cycle. Returns false once duration_s is reached. Real-time safe.
  bool step();
  /// start() (if not started) and step() until the end.
  void run();

  double time_s() const { return t_s_; }
  const SessionMetrics& metrics() const { return metrics_; }
  const SafetyLayer& safety() const { return safety_; }
  SafetyLayer& safety() { return safety_; }
  const BilateralController& controller() const { return *controller_; }
  const DelayChannel<SlaveCommand>& forward() const { return forward_; }
  const DelayChannel<SlaveSample>& backward() const { return backward_; }
  /// Newest metrics sample (what was logged this cycle).
  const MetricsSample& last_sample() const { return last_; }
  /// Force written to the device this cycle [N].
  const Eigen::Vector3d& device_force_n() const { return last_.device_force_n; }
  /// Newest slave sample the master has.
  const SlaveSample& slave_at_master() const { return slave_rx_; }
  /// Newest command the slave has (what it stepped with this cycle).
  const SlaveCommand& slave_command() const { return slave_cmd_; }
  /// Force the controller asked for before the safety layer this cycle [N].
  const Eigen::Vector3d& controller_force_n() const { return controller_force_n_; }
  /// Fault injection: while true, every slave sample is lost on the way back (a dead link).
  void set_backward_outage(bool down) { backward_outage_ = down; }
  /// Summary JSON: metrics plus both channels' delay and loss.
  std::string summary_json() const;

 private:
  LoopbackConfig cfg_;
  HapticDevice& device_;
  SlaveSimulator& slave_;
  std::unique_ptr<BilateralController> controller_;
  DelayChannel<SlaveCommand> forward_;
  DelayChannel<SlaveSample> backward_;
  SafetyLayer safety_;
  SessionMetrics metrics_;
  MetricsSample last_;
  SlaveSample slave_rx_;    // newest sample at the master
  SlaveCommand slave_cmd_;  // newest command at the slave
  double last_rx_s_ = -1.0;
  double t_s_ = 0.0;
  bool started_ = false;
  bool backward_outage_ = false;
  Eigen::Vector3d controller_force_n_ = Eigen::Vector3d::Zero();
};

/// JSON object of a channel report: {"delay_mean_ms":..,"delay_p50_ms":..,...}.
std::string channel_json(const ChannelReport& r);

}  // namespace teleop::master
