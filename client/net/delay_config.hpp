#pragma once
// Configuration of an injected network impairment (one direction): constant delay, jitter,
// reordering, Bernoulli loss and Gilbert-Elliott burst loss, scheduled faults, with a seed.
// Each parameter (YAML key, flag, unit, range, help) is declared once in the table of
// client/net/delay_params.hpp, which validate(), the flag parser and the YAML loader read:
//
// Flags:   --delay 50ms --jitter 5ms --jitter-dist uniform|normal --reorder --loss 1%
//          --burst-loss p_gb,p_bg --delay-spike at,duration,extra --loss-window at,duration,loss
//          --seed N --channel-capacity N
// YAML:    {delay: 50ms, jitter: 5ms, jitter_dist: normal, reorder: false, loss: 1%,
//           burst_loss: [0.01, 0.3], delay_spike: [3s, 1s, 1s], seed: 7, capacity: 4096}
// A duration flag needs its unit (s, ms, us, ns; "--delay 5" is refused, "0" alone is
// allowed); in YAML a plain number is seconds. Probabilities may be plain numbers in [0, 1].
#include <cstddef>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "common/config/config.hpp"

namespace teleop::master {

/// Shape of the jitter added to the constant delay.
enum class JitterDist : std::uint8_t {
  kUniform = 0,  ///< delay uniform in [D - J, D + J] (standard deviation J / sqrt(3))
  kNormal = 1,   ///< delay normal N(D, J^2), truncated to D +- 4 J
};

/// One direction of the impaired link. Defaults: a perfect link.
struct DelayConfig {
  double delay_s = 0.0;   ///< D: constant one-way delay [s]
  double jitter_s = 0.0;  ///< J: jitter scale [s] (see JitterDist)
  JitterDist jitter_dist = JitterDist::kUniform;
  bool reorder = false;              ///< false: a sample never overtakes an earlier one
  double loss_probability = 0.0;     ///< Bernoulli loss per sample [0, 1]
  bool burst_loss = false;           ///< Gilbert-Elliott two-state loss on
  double burst_p_good_to_bad = 0.0;  ///< p_gb per sample [0, 1]
  double burst_p_bad_to_good = 1.0;  ///< p_bg per sample (0, 1]; bad state loses all
  std::uint64_t seed = 1;            ///< random seed (mt19937_64)
  std::size_t capacity = 4096;       ///< samples in flight at most (overflow drops)
  // Scheduled faults, in seconds after the channel's first sample (the fault suite's "a 1 s
  // delay spike", "a 50 % loss burst"): samples sent in [at, at + duration) get `extra` more
  // delay (FIFO: the ones after queue behind them) / are lost with probability `p`.
  double spike_at_s = 0.0, spike_duration_s = 0.0, spike_extra_s = 0.0;
  double window_at_s = 0.0, window_duration_s = 0.0, window_loss = 0.0;

  /// Checks every field against delay_param_table(). @throws ConfigError naming the parameter,
  /// the value and the allowed range.
  void validate() const;
  /// One-line human-readable summary ("delay 50 ms, jitter 5 ms uniform, loss 1 %, ...").
  std::string describe() const;
  /// Stationary loss fraction expected from the loss model (Bernoulli and burst combined).
  double expected_loss() const;
  /// Standard deviation of the delay expected from the jitter model [s] (before clipping).
  double expected_jitter_stddev_s() const;
};

/// Applies one flag (e.g. "--delay", "50ms"). Returns false if `flag` is not a delay flag.
/// "--reorder" takes no value (pass an empty `value`). @throws ConfigError on a bad value.
bool apply_delay_flag(DelayConfig& cfg, const std::string& flag, const std::string& value);
/// True if `flag` is a delay flag that takes a value.
bool delay_flag_takes_value(const std::string& flag);
/// Consumes the delay flags in `args` (["--delay", "50ms", "--reorder", ...]), validates,
/// and returns the words it did not recognise, in order. @throws ConfigError.
std::vector<std::string> parse_delay_flags(DelayConfig& cfg, const std::vector<std::string>& args);
/// Reads a delay mapping; unknown keys are rejected. @throws ConfigError naming the field.
DelayConfig delay_config_from_yaml(const config::Node& node);

/// Portable random numbers: mt19937_64 (fully specified by the standard) with hand-written
/// distributions, so a seed gives the same sequence on every standard library.
class PortableRng {
 public:
  explicit PortableRng(std::uint64_t seed = 1) : gen_(seed) {}
  void seed(std::uint64_t s) {
    gen_.seed(s);
    have_spare_ = false;
  }
  /// Uniform in [0, 1) with 53 random bits.
  double uniform01() { return static_cast<double>(gen_() >> 11) * (1.0 / 9007199254740992.0); }
  /// Uniform in [a, b).
  double uniform(double a, double b) { return a + (b - a) * uniform01(); }
  /// Standard normal (Box-Muller, polar-free form, both values used).
  double normal();
  /// True with probability p.
  bool bernoulli(double p) { return p > 0.0 && uniform01() < p; }

 private:
  std::mt19937_64 gen_;
  double spare_ = 0.0;
  bool have_spare_ = false;
};

}  // namespace teleop::master
