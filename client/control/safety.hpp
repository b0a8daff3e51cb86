#pragma once
// Safety layer between the controller and the device.
//
// It scales the controller's force by s in [0, 1] and raises events (teleop::sim::EventQueue,
// kinds = EVENT_* of idl/Teleop.idl; header-only, no link dependency on teleop::sim):
//   - link lost: no slave sample for link_timeout_s -> s ramps to 0 over link_fade_s;
//     when samples return, s ramps back to 1 over link_fade_s (EVENT_WATCHDOG both ways);
//   - cut (latched until rearm()): the verdict became unstable, or the force sat at the
//     limit for longer than saturation_limit_s, or the passivity energy keeps falling below
//     -energy_limit (metrics.energy_growing()) -> s ramps to 0 over cut_fade_s (EVENT_SAFETY);
//   - thermal limit: a first-order average of |F| (time constant continuous_tau_s) above the
//     spec's max continuous force clamps |F| to that force until it cools (EVENT_LIMIT);
//   - non-finite force: zero force for that cycle, counted (EVENT_FAULT);
//   - rate bound: the force written never changes by more than the spec's
//     max_force_rate_n_per_s times the period in one cycle, whatever the controller, a
//     returning link, a cut or a re-homing asks (cycles where it acted are counted);
//   - hold_zero(): cycles where nothing is rendered (homing, refused, closing) bring the force
//     to zero at that rate instead of dropping it.
// The output never exceeds the spec's peak force. filter() allocates nothing.
#include <cstdint>

#include "client/device/haptic_device.hpp"
#include "client/metrics/session_metrics.hpp"
#include "common/sim/events.hpp"

namespace teleop::master {

/// Safety thresholds. Defaults with units.
struct SafetyParams {
  double link_timeout_s = 0.1;      ///< no slave sample for this long = link lost [s]
  double link_fade_s = 0.2;         ///< fade-out (and fade-in) time on link loss [s]
  double cut_fade_s = 0.05;         ///< fade-out time of a cut [s]
  double saturation_limit_s = 0.3;  ///< continuous time at the force limit that cuts [s]
  bool cut_on_unstable = true;      ///< cut when the metrics' verdict becomes unstable
  bool cut_on_energy = true;        ///< cut when the energy keeps growing
  bool thermal_limit = true;        ///< enforce the spec's max continuous force
  double continuous_tau_s = 1.0;    ///< averaging time constant of the thermal model [s]
};

/// Safety state.
enum class SafetyState : std::uint8_t {
  kNormal = 0,    ///< force passes (possibly thermally limited)
  kLinkLost = 1,  ///< fading because the link is lost
  kCut = 2,       ///< fading or faded after a cut; latched
};

/// The safety layer. See the file comment.
class SafetyLayer {
 public:
  SafetyLayer() = default;
  /// Sets thresholds and the device spec; resets the state.
  void configure(const SafetyParams& params, const DeviceSpec& spec);
  /// Clears a latched cut and restarts with the force faded in from zero.
  void rearm();
  /// The next filter() calls fade the force in from zero over link_fade_s (after a re-homing).
  void fade_in() { scale_ = 0.0; }

  /// A cycle with nothing to render (homing, refused, closing): the force goes to zero at the
  /// spec's rate bound. Returns the force to write. Real-time safe.
  Eigen::Vector3d hold_zero(double dt_s);

  /// One cycle: `now_s` master clock [s], `dt_s` period, `force_n` the controller's force,
  /// `last_slave_rx_s` master time the newest slave sample arrived (negative: never),
  /// `limit_n` the controller's saturation limit, `metrics` for verdict and energy.
  /// Returns the force to write. Real-time safe.
  Eigen::Vector3d filter(double now_s, double dt_s, const Eigen::Vector3d& force_n,
                         double last_slave_rx_s, double limit_n, const SessionMetrics& metrics);

  SafetyState state() const { return state_; }
  /// Current force scale [0, 1].
  double scale() const { return scale_; }
  /// True while the link is considered lost.
  bool link_lost() const { return link_lost_; }
  /// True once a cut happened (until rearm()).
  bool cut() const { return state_ == SafetyState::kCut; }
  /// Why the last cut happened ("" if none).
  const char* cut_reason() const { return cut_reason_; }
  /// Time of the cut [s] (negative if none).
  double cut_time_s() const { return cut_time_s_; }
  /// Largest force written [N].
  double max_output_n() const { return max_out_; }
  /// Events raised (the node drains and publishes them on teleop/events).
  teleop::sim::EventQueue& events() { return events_; }
  /// Number of non-finite forces replaced by zero.
  std::uint64_t faults() const { return faults_; }
  /// Cycles in which the rate bound changed the force.
  std::uint64_t rate_limited_cycles() const { return rate_limited_; }
  /// Largest change of the force written between two cycles [N].
  double max_step_n() const { return max_step_n_; }
  /// Force written in the last cycle [N].
  const Eigen::Vector3d& last_output_n() const { return last_out_; }

 private:
  void do_cut(double now_s, const char* reason);
  /// Moves the output towards `target` by at most the rate bound; records the output.
  Eigen::Vector3d limit_rate(const Eigen::Vector3d& target, double dt_s);

  SafetyParams p_;
  DeviceSpec spec_;
  SafetyState state_ = SafetyState::kNormal;
  double scale_ = 1.0;
  bool link_lost_ = false;
  bool thermal_limited_ = false;
  double sat_time_s_ = 0.0;
  double f_avg_n_ = 0.0;
  double max_out_ = 0.0;
  double cut_time_s_ = -1.0;
  const char* cut_reason_ = "";
  std::uint64_t faults_ = 0;
  std::uint64_t rate_limited_ = 0;
  double max_step_n_ = 0.0;
  Eigen::Vector3d last_out_ = Eigen::Vector3d::Zero();
  teleop::sim::EventQueue events_;
};

}  // namespace teleop::master
