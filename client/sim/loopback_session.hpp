#pragma once
// LoopbackSession: the whole bilateral loop in one process, without DDS, at a fixed period.
// The master half is the same MasterCycle teleop_master runs; the link is an in-process slave:
//
//   cycle.step:   link.receive -> backward channel -> controller -> safety -> device.write
//                 -> forward channel -> link.send (the newest due command)
//   slave:        slave.step(newest command) -> its sample waits in the link for the next cycle
//   cycle.finish: metrics from the slave's ground truth -> verdict -> device.advance(dt)
//
// It is what the delay-robustness sweep, the experiments and the tests run. step() allocates
// nothing.
#include <memory>
#include <string>

#include "client/cycle/master_cycle.hpp"
#include "common/control/slave_simulator.hpp"

namespace teleop::master {

/// Everything a loopback run needs besides the device and the slave: the master cycle's
/// configuration (its delivery is always the newest due command) and the run length.
struct LoopbackConfig : MasterCycleConfig {
  double duration_s = 5.0;  ///< run() length [s]; with homing, counted from its end
  /// 0: start() puts the slave at the mapped device position and the controller runs from the
  /// first cycle. Above 0: as teleop_master does against a live server, the slave stays where
  /// it is (a robot at home) and the cycle homes it there along a path of this length first;
  /// no force is rendered and no metrics are recorded until homing is over [s].
  double homing_s = 0.0;
};

/// The in-process loop. See the file comment.
class LoopbackSession {
 public:
  /// Allocates channels and the controller. @throws ConfigError on bad configuration.
  LoopbackSession(const LoopbackConfig& cfg, HapticDevice& device, SlaveSimulator& slave);

  /// Configures and activates device and controller; puts the slave at the mapped device
  /// position (or, with homing_s > 0, starts homing it from where it is). Call once before
  /// step().
  void start();
  /// One cycle. Returns false once duration_s is reached (with homing: duration_s after the
  /// homing ended). Real-time safe.
  bool step();
  /// start() (if not started) and step() until the end.
  void run();

  double time_s() const { return t_s_; }
  const MasterCycle& cycle() const { return cycle_; }
  const SessionMetrics& metrics() const { return cycle_.metrics(); }
  const SafetyLayer& safety() const { return cycle_.safety(); }
  SafetyLayer& safety() { return cycle_.safety(); }
  const BilateralController& controller() const { return cycle_.controller(); }
  const DelayChannel<SlaveCommand>& forward() const { return cycle_.forward(); }
  const DelayChannel<SlaveSample>& backward() const { return cycle_.backward(); }
  /// Newest metrics sample (what was logged this cycle).
  const MetricsSample& last_sample() const { return cycle_.last_sample(); }
  /// Force written to the device this cycle [N].
  const Eigen::Vector3d& device_force_n() const { return cycle_.device_force_n(); }
  /// Newest slave sample the master has.
  const SlaveSample& slave_at_master() const { return cycle_.slave_at_master(); }
  /// Newest command the slave has (what it stepped with this cycle).
  const SlaveCommand& slave_command() const { return link_.command; }
  /// Force the controller asked for before the safety layer this cycle [N].
  const Eigen::Vector3d& controller_force_n() const { return cycle_.controller_force_n(); }
  /// Fault injection: while true, every slave sample is lost on the way back (a dead link).
  void set_backward_outage(bool down) { link_.outage = down; }
  /// Summary JSON: metrics plus both channels' delay and loss.
  std::string summary_json() const;

 private:
  /// The in-process transport: the newest command for the slave, the slave's newest sample
  /// for the master (stamped with the time the slave produced it).
  struct Link final : SlaveLink {
    SlaveCommand command;
    SlaveSample sample;
    double sample_at_s = 0.0;
    bool pending = false;
    bool outage = false;
    void send(const SlaveCommand& c) override { command = c; }
    bool receive(double /*now_s*/, SlaveSample& s, double& at_s) override {
      if (!pending) return false;
      pending = false;
      s = sample;
      at_s = sample_at_s;
      return true;
    }
  };

  static MasterCycleConfig cycle_config(const LoopbackConfig& cfg);

  LoopbackConfig cfg_;
  SlaveSimulator& slave_;
  Link link_;
  MasterCycle cycle_;
  double t_s_ = 0.0;
  bool started_ = false;
};

}  // namespace teleop::master
