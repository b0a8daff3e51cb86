#pragma once
// Live tuning of a running master (teleop/tuning, idl/Teleop.idl): which gains and injected
// delays a request may change, within which bounds, and how the change is applied without a
// force step.
//
// A request names the fields it sets (TuningField bits). check_tuning() accepts it only if every
// field is one the running scheme uses and every value is finite and within TuningLimits (the
// device spec caps the master's stiffness and damping, as configure() does; the controller's
// configuration ranges cap the rest; a delay is capped by what the delay channel can hold).
// TuningRamp then moves each value from where it is to the target linearly over the request's
// ramp time, and the injected delays at most kMaxDelaySlewSPerS seconds per second, so the
// delivery times of the channel never bunch up or jump. The safety layer's force-rate bound
// stays in force on top. Everything here is real-time safe except check_tuning()'s message and
// describe(), which run once per request.
#include <cstdint>
#include <string>

#include "client/control/bilateral_controller.hpp"

namespace teleop::master {

/// Fields a tuning request may set (bit values of idl TUNE_*).
enum TuningField : std::uint32_t {
  kTuneMasterStiffness = 1,  ///< K_pm [N/m]
  kTuneMasterDamping = 2,    ///< B_m [N s/m]
  kTuneForceGain = 4,        ///< K_f [-]
  kTuneSlaveStiffness = 8,   ///< K_ps [N/m]
  kTuneForwardDelay = 16,    ///< injected master -> slave delay [s]
  kTuneBackwardDelay = 32,   ///< injected slave -> master delay [s]
  kTuneAll = 63,
};

/// Values of the tunable parameters (a request's targets, or the values in force).
struct TuningValues {
  double master_stiffness_n_per_m = 0.0;
  double master_damping_ns_per_m = 0.0;
  double force_gain = 0.0;
  double slave_stiffness_n_per_m = 0.0;
  double forward_delay_s = 0.0;
  double backward_delay_s = 0.0;
};

/// A tuning request, transport-neutral.
struct TuningRequestData {
  std::uint32_t fields = 0;  ///< TuningField bits
  TuningValues values;       ///< targets of the fields set
  double ramp_s = 0.5;       ///< time to move to the targets [s]
};

/// What a master accepts.
struct TuningLimits {
  std::uint32_t tunable = 0;  ///< TuningField bits the scheme uses
  double max_master_stiffness_n_per_m = 0.0;
  double max_master_damping_ns_per_m = 0.0;
  double max_force_gain = 0.0;
  double max_slave_stiffness_n_per_m = 0.0;
  double max_delay_s = 0.0;
  double min_ramp_s = 0.05;  ///< a shorter ramp is raised to this
  double max_ramp_s = 10.0;
};

/// Largest rate at which a live injected delay changes [s of delay per s].
inline constexpr double kMaxDelaySlewSPerS = 0.25;

/// The fields a scheme uses: the gains its traits name (SchemeTraits::tunable_gains, which may
/// depend on its parameters), and the delays always.
/// @throws ConfigError naming the allowed schemes if params.scheme is unknown.
std::uint32_t tunable_fields(const ControllerParams& params);

/// Bounds for `params` on a device with `spec`; `channel_capacity` samples at `dt_s` per cycle
/// cap the delay (at 80 % of what the channel holds, and at 2 s).
TuningLimits tuning_limits(const ControllerParams& params, const DeviceSpec& spec,
                           std::size_t channel_capacity, double dt_s);

/// Empty if `request` may be applied, else why not, naming the field, its value and the
/// allowed range (or that the scheme does not use the field).
std::string check_tuning(const TuningRequestData& request, const TuningLimits& limits,
                         const std::string& scheme);

/// "K_f 1 -> 1.5, forward delay 0 -> 100 ms over 0.5 s": the fields `request` changes.
std::string describe_tuning(const TuningRequestData& request, const TuningValues& from,
                            double ramp_s);

/// Moves the values in force toward the targets of accepted requests. See the file comment.
class TuningRamp {
 public:
  /// Starts from the values in force.
  void reset(const TuningValues& now) {
    from_ = now;
    current_ = now;
    target_ = now;
    active_ = false;
  }
  /// Sets new targets for the fields of `request` (already checked), from the current values,
  /// starting at `now_s`. Fields not in the request keep their targets.
  void start(const TuningRequestData& request, double now_s, double min_ramp_s);
  /// Values at `now_s`. Returns true while a ramp is under way (or just ended this call).
  bool advance(double now_s);

  const TuningValues& current() const { return current_; }
  const TuningValues& target() const { return target_; }
  bool active() const { return active_; }

 private:
  TuningValues from_, current_, target_;
  double start_s_ = 0.0;
  double ramp_s_ = 0.0;
  double forward_ramp_s_ = 0.0;
  double backward_ramp_s_ = 0.0;
  bool active_ = false;
};

}  // namespace teleop::master
