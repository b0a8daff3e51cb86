#pragma once
// MasterCycle: one haptic cycle of the master, the same for teleop_master (DDS) and for the
// in-process loopback session (tests, the delay sweep, experiments):
//
//   link.receive -> backward delay channel -> controller.update (newest slave sample)
//   -> safety.filter -> device.write -> forward delay channel -> link.send      (step)
//   -> metrics.update (slave at the master, or the slave's truth in-process)
//   -> losses, verdict, device.advance(dt)                                       (finish)
//
// Before the session the cycle may home: the slave is brought along a minimum-jerk path from
// where it is to the mapped device position while no force is rendered; the controller is
// activated once the slave is there. During the session it re-homes the same way, from where
// the slave is to where the device is now, whenever master and slave may have parted: the link
// came back after a loss, the slave restarted (SlaveLink::restarts()), or the caller says so
// (rehome(): a takeover of the slave). The force goes to zero at the device's rate bound while
// homing and fades in from zero after it (SafetyLayer), so none of these makes a force step.
// hold() keeps the cycle rendering nothing and commanding nothing (a master refused the
// slave). A device whose readings stop (a driver process that quit or hangs: the external
// device's samples go stale) for longer than driver_timeout_s is silent: the cycle holds the
// same way, counts the silence and its length and raises an event; when readings return it
// re-homes (the hand may have moved meanwhile). Cycles without a valid reading are not part
// of the session's figures. The clock is an argument (seconds on any steady clock); metrics time
// counts from start(). step() and finish() allocate nothing.
#include <Eigen/Core>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "client/control/bilateral_controller.hpp"
#include "client/control/safety.hpp"
#include "client/control/tuning.hpp"
#include "client/cycle/slave_link.hpp"
#include "client/device/haptic_device.hpp"
#include "client/metrics/session_metrics.hpp"
#include "client/net/delay_channel.hpp"

namespace teleop::master {

/// How the forward channel's due commands reach the link each cycle.
enum class ForwardDelivery {
  kEveryDue,   ///< every due command, in delivery order (a network carries each one)
  kNewestDue,  ///< only the newest due command (an in-process slave reads one per step)
};

/// Why a session re-homed.
enum class RehomeReason : std::uint8_t {
  kLinkBack = 0,      ///< slave samples came back after a link loss
  kSlaveRestart = 1,  ///< the slave restarted (new server instance)
  kTakeover = 2,      ///< this master took the slave over from another
  kDriverBack = 3,    ///< the device's readings came back after a silence
};
const char* to_string(RehomeReason r);

/// Everything a master cycle needs besides the device and the link.
struct MasterCycleConfig {
  ControllerParams controller;  ///< scheme, gains, workspace map
  DelayConfig forward;          ///< master -> slave injected impairment
  DelayConfig backward;         ///< slave -> master injected impairment
  SafetyParams safety;          ///< safety layer thresholds
  bool safety_enabled = true;   ///< false: the controller's force goes straight to the device
  VerdictParams verdict;        ///< verdict thresholds
  double dt_s = 1e-3;           ///< haptic period [s]
  ForwardDelivery delivery = ForwardDelivery::kEveryDue;
  std::uint32_t session_id = 0;     ///< passivity session id sent to the slave (0: controller's)
  bool rehome_on_link_back = true;  ///< re-home when samples return after a link loss
  double rehome_speed_mps = 0.1;    ///< re-homing path length / duration, slave frame [m/s]
  double rehome_min_s = 0.1;        ///< shortest re-homing path [s]
  double rehome_max_s = 3.0;        ///< longest re-homing path [s]
  /// A command goes to the slave every this many cycles (a haptic loop faster than the network,
  /// e.g. model-mediated at 4 kHz with commands at 1 kHz); slave samples are taken every cycle.
  std::uint32_t command_every = 1;
  /// A device without a valid reading for longer than this is silent: the slave holds and the
  /// force fades to zero at the rate bound until readings return [s], (0, 10].
  double driver_timeout_s = 0.1;
};

/// One master cycle. See the file comment.
class MasterCycle {
 public:
  /// Allocates channels and the controller. @throws ConfigError on bad configuration.
  MasterCycle(const MasterCycleConfig& cfg, HapticDevice& device, SlaveLink& link);

  /// Configures and activates device, controller and safety; clears channels and metrics.
  /// Metrics time counts from `now_s`. Without homing the controller is activated at once.
  void start(double now_s);
  /// Homes instead: the slave goes from `slave_tip_m` to the mapped device position along a
  /// minimum-jerk path of `duration_s`, then (once within `tolerance_m`, or `timeout_s` after
  /// the path ended) the controller is activated. No force is rendered while homing.
  void start_homing(double now_s, const Eigen::Vector3d& slave_tip_m, double duration_s,
                    double tolerance_m = 0.005, double timeout_s = 3.0);

  /// Re-homes now (see the file comment): the controller stops, the force goes to zero at the
  /// rate bound, the slave goes from where it is to the mapped device position, then the
  /// controller restarts (a new passivity session) and the force fades in. Real-time safe.
  void rehome(double now_s, RehomeReason why);
  /// While on, the cycle renders nothing (force to zero at the rate bound), runs no
  /// controller and sends commands that hold the slave (enabled = false); its cycles are not
  /// part of the session's figures. Turning it off does not restart the controller: call
  /// rehome() for that.
  void hold(bool on) { held_ = on; }
  bool held() const { return held_; }

  /// Live tuning (client/control/tuning.hpp): checks `request` against tuning_limits() and,
  /// if it passes, ramps the gains and the injected delays to its values from `now_s`. Returns
  /// an empty string, or why it was rejected (field, value, range). Called between cycles: its
  /// message allocates; the ramp runs in step() and allocates nothing.
  std::string tune(const TuningRequestData& request, double now_s);
  const TuningLimits& tuning_limits() const { return tuning_limits_; }
  /// Values in force now (current()) and the targets of the newest accepted request (target()).
  const TuningRamp& tuning() const { return tuning_; }
  /// Cycles whose device reading lay outside the workspace box the device declared (by more
  /// than kWorkspaceTolerance_m): treated as no reading (zero force, the slave holds).
  std::uint64_t workspace_violations() const { return workspace_violations_; }
  static constexpr double kWorkspaceTolerance_m = 0.005;
  std::uint64_t tunings_accepted() const { return tunings_accepted_; }
  std::uint64_t tunings_rejected() const { return tunings_rejected_; }

  /// The master half of a cycle (see the file comment). Real-time safe.
  void step(double now_s);
  /// Closes the cycle: metrics from the newest slave sample at the master, or from
  /// `slave_truth` when the caller knows the slave's true state (in-process). Real-time safe.
  void finish(double now_s, const SlaveSample* slave_truth = nullptr);

  /// Deactivates the controller and the device (zero force written first).
  void stop();

  bool homing() const { return homing_; }
  /// Re-homings so far in this session, and why the last one happened.
  std::uint64_t rehomes() const { return rehomes_; }
  std::uint64_t rehomes(RehomeReason why) const {
    return rehomes_by_[static_cast<std::size_t>(why)];
  }
  /// Driver silences (see the file comment): how many began, whether one lasts now, and the
  /// time silent so far [s] (from the last valid reading, the ongoing silence included).
  std::uint64_t driver_silences() const { return driver_silences_; }
  bool driver_silent() const { return driver_silent_; }
  double driver_silent_s(double now_s) const {
    return driver_silent_total_s_ + (driver_silent_ ? now_s - invalid_since_s_ : 0.0);
  }
  /// True from rehome() until the controller runs again.
  bool rehoming() const { return homing_ && session_start_s_ >= 0.0; }
  /// True if the last step() was a homing cycle (nothing rendered, no metrics recorded).
  bool homing_cycle() const { return homing_cycle_; }
  /// Time the session proper began (homing over) [s]; negative while homing.
  double session_start_s() const { return session_start_s_; }
  /// Seq of the newest command issued into the forward channel.
  std::uint64_t command_seq() const { return seq_; }
  /// True if a new slave sample reached the controller this cycle.
  bool sample_arrived() const { return sample_arrived_; }

  const DeviceReading& reading() const { return reading_; }
  /// Newest slave sample the master has (after the backward channel).
  const SlaveSample& slave_at_master() const { return newest_; }
  /// Newest metrics sample (what was recorded this cycle).
  const MetricsSample& last_sample() const { return sample_; }
  /// Force written to the device this cycle [N].
  const Eigen::Vector3d& device_force_n() const { return force_n_; }
  /// Force the controller asked for before the safety layer this cycle [N].
  const Eigen::Vector3d& controller_force_n() const { return controller_force_n_; }
  const SessionMetrics& metrics() const { return metrics_; }
  SessionMetrics& metrics() { return metrics_; }
  const SafetyLayer& safety() const { return safety_; }
  SafetyLayer& safety() { return safety_; }
  const BilateralController& controller() const { return *controller_; }
  const DelayChannel<SlaveCommand>& forward() const { return forward_; }
  const DelayChannel<SlaveSample>& backward() const { return backward_; }
  const MasterCycleConfig& config() const { return cfg_; }
  const DeviceSpec& device_spec() const { return device_.spec(); }

 private:
  void prepare(double now_s);
  void end_homing(double now_s);
  void homing_step(double now_s);
  /// A cycle that renders nothing (force to zero at the rate bound) and commands the slave to
  /// `target_m` (enabled) or to hold (not enabled); not part of the session's figures.
  void render_nothing(const Eigen::Vector3d& target_m, bool enabled);
  void check_rehome(double now_s);
  void check_workspace(double now_s);
  void check_driver(double now_s);

  MasterCycleConfig cfg_;
  HapticDevice& device_;
  SlaveLink& link_;
  std::unique_ptr<BilateralController> controller_;
  DelayChannel<SlaveCommand> forward_;
  DelayChannel<SlaveSample> backward_;
  SafetyLayer safety_;
  // the master's position and felt force (slave frame) when each command was sent, by seq
  static constexpr std::uint64_t kSentRing = 8192;
  std::vector<Eigen::Vector3d> sent_position_m_, sent_force_n_;
  SessionMetrics metrics_;

  DeviceReading reading_;
  SlaveSample newest_;    // newest sample at the master
  MetricsSample sample_;  // this cycle's metrics sample
  SlaveCommand command_;  // this cycle's command
  Eigen::Vector3d force_n_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d controller_force_n_ = Eigen::Vector3d::Zero();
  double origin_s_ = 0.0;    // metrics time zero
  double last_rx_s_ = -1.0;  // when the controller last got a new sample
  std::uint64_t seq_ = 0;
  std::uint64_t cycles_ = 0;
  bool sample_arrived_ = false;
  bool homing_cycle_ = false;  // this cycle was a homing cycle (no metrics)

  // homing
  bool homing_ = false;
  double session_start_s_ = -1.0;
  double homing_start_s_ = 0.0;
  double homing_duration_s_ = 0.0;
  double homing_tolerance_m_ = 0.005;
  double homing_timeout_s_ = 3.0;
  Eigen::Vector3d homing_from_m_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d homing_goal_m_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d homing_target_m_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d slave_tip_m_ = Eigen::Vector3d::Zero();  // where the slave is, as known
  bool track_goal_ = false;                                // re-homing: the goal follows the device
  bool held_ = false;
  bool link_was_lost_ = false;  // the link was lost while the controller ran
  std::uint32_t epoch_seen_ = 0;
  bool have_epoch_ = false;
  std::uint64_t rehomes_ = 0;
  std::uint64_t rehomes_by_[4] = {0, 0, 0, 0};
  // driver silence
  double invalid_since_s_ = -1.0;  // first cycle of the current run without a valid reading
  bool driver_silent_ = false;
  std::uint64_t driver_silences_ = 0;
  double driver_silent_total_s_ = 0.0;  // silences that ended [s]
  std::uint32_t next_session_id_ = 0;
  std::uint64_t workspace_violations_ = 0;
  bool outside_workspace_ = false;
  // live tuning
  TuningLimits tuning_limits_;
  TuningRamp tuning_;
  std::uint64_t tunings_accepted_ = 0;
  std::uint64_t tunings_rejected_ = 0;
};

/// A channel report as a JSON object: {"pushed":..,"delay_mean_ms":..,"delay_p50_ms":..,...}.
nlohmann::ordered_json channel_fields(const ChannelReport& r);
/// channel_fields(r) written compact.
std::string channel_json(const ChannelReport& r);

/// Minimum-jerk blend s(t) in [0, 1] for t in [0, T].
double min_jerk(double t_s, double duration_s);

}  // namespace teleop::master
