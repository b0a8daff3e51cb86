#pragma once
// Session metrics of a bilateral teleoperation run, and an online stability verdict.
//
// update() is called once per haptic cycle (allocation-free) with a MetricsSample. It keeps:
//   - master-slave position error e = |x_m(slave frame) - x_s| (RMS, max) [m]
//   - rendered force vs environment force: |F_device - beta R^T f_e| over contact samples
//     (RMS) [N]
//   - contact time [s]
//   - the passivity observer of the master port (Hannaford & Ryu 2002):
//        E(n) = dT sum_k P(k),   P = -F_device . v_m   [J]
//     P is the power flowing from the operator INTO the teleoperator (the operator pushes on
//     the handle with -F_device in quasi-statics). E >= 0 means the teleoperator has so far
//     absorbed at least the energy it returned (passive); E going ever more negative means
//     it generates energy.
//   - the verdict, evaluated at the end of each window of window_s:
//       unstable    force saturated for more than saturation_fraction of a window, or the
//                   oscillation amplitude grew for growth_windows windows in a row, or the
//                   energy E is below -energy_limit_j and fell during each of the last
//                   energy_windows windows (the teleoperator keeps generating energy: a
//                   passive one started at rest has E >= 0), or a non-finite value was seen;
//       oscillating at least sustain_windows consecutive windows each with >= min_crossings
//                   velocity zero crossings (hysteresis +-velocity_threshold_mps on any axis);
//       stable      otherwise.
//       out-of-spec the device was driven beyond its continuous force rating: |F_device| above
//                   the rating for more than spec_time_s in all (peaks within the peak rating
//                   are what the peak rating is for; a scheme that keeps pushing that hard is
//                   not), or its first-order average (time constant spec_tau_s, the safety
//                   layer's thermal model) above the rating;
//     The session verdict is the worst window verdict (unstable latches), in the order stable <
//     oscillating < out-of-spec < unstable.
//
// Transparency, what the operator feels (docs/control.md, "Transparency"):
//   - free space (slave not in contact, link ok): |F_device| mean, p99 (5 mN bins), max;
//   - in contact: the force felt, F_device along the contact normal in the slave's units
//     (felt_force_n), against the environment's |f_e| (contact_force_n): ratio of the sums and
//     the RMS of the difference;
//   - stiffness, from the loading phase of each contact: the samples at which both sides press
//     in, the slave's depth (slave_depth_m) and the master's (its position along the contact
//     normal, master_depth_m = slave_depth_m + n . (x_s - x_m)) each 2 um deeper than at the
//     previous sample taken in that contact (not holding, slipping, trembling or letting go),
//     each weighted by the depth it gained (uniform in depth, whatever the speed): the weighted
//     least-squares line F = k x + b of the felt force against the master's depth and of |f_e|
//     against the slave's depth: felt and environment stiffness k, and their ratio (1 is
//     transparent; below 1 the object feels softer than it is, e.g. force-position's slave
//     lagging behind the master by its tracking error; near 0 the force felt does not grow as
//     the operator presses in: a drag felt as much in free space, or a force that arrives a
//     round trip later). The offset b takes the force already there at the touch. The master's
//     side of a sample is taken when it sent the command the slave's sample echoes (both sides
//     at the same moment of the exchange, over a network and in-process alike).
#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <string>

namespace teleop::master {

/// Verdict of a run. From best to worst: stable, oscillating, out of spec, unstable.
enum class Verdict : std::uint8_t { kStable = 0, kOscillating = 1, kUnstable = 2, kOutOfSpec = 3 };
/// "stable" | "oscillating" | "unstable" | "out-of-spec".
const char* verdict_name(Verdict v);

/// Thresholds of the verdict (see the file comment). Defaults suit a 1 kHz desk device.
struct VerdictParams {
  double window_s = 0.5;                 ///< evaluation window [s]
  double velocity_threshold_mps = 0.02;  ///< hysteresis band for zero crossings [m/s]
  int min_crossings = 5;                 ///< crossings per window counted as oscillation
  int sustain_windows = 2;               ///< consecutive oscillating windows = sustained
  double growth_ratio = 1.2;             ///< peak |v| ratio window/previous counted as growth
  int growth_windows = 2;                ///< consecutive growing windows = unstable
  double saturation_fraction = 0.3;      ///< share of a window at the force limit = unstable
  double energy_limit_j = 0.2;           ///< generated energy that counts as unstable [J]
  double spec_tau_s = 1.0;    ///< averaging time of |F| against the continuous rating [s]
  double spec_time_s = 0.25;  ///< time above the continuous rating that is out of spec [s]
  int energy_windows = 1;     ///< windows in a row with E < -limit and falling
  double settle_s = 0.0;      ///< windows ending before this are not judged [s]
};

/// One haptic cycle as the metrics see it.
struct MetricsSample {
  double time_s = 0.0;  ///< master clock [s]
  double dt_s = 1e-3;   ///< cycle period [s]
  Eigen::Vector3d master_position_m =
      Eigen::Vector3d::Zero();                                 ///< master mapped to slave frame [m]
  Eigen::Vector3d slave_position_m = Eigen::Vector3d::Zero();  ///< slave tip, slave frame [m]
  Eigen::Vector3d master_velocity_mps = Eigen::Vector3d::Zero();  ///< device frame [m/s]
  Eigen::Vector3d device_force_n = Eigen::Vector3d::Zero();  ///< force written, device frame [N]
  Eigen::Vector3d environment_force_n =
      Eigen::Vector3d::Zero();  ///< beta R^T f_e, master frame [N]
  double force_limit_n = 10.0;  ///< the saturation limit in force [N]
  bool in_contact = false;      ///< slave touches the environment
  bool have_slave = true;       ///< a slave sample is known (else no position error counted)
  bool link_ok = true;          ///< slave samples arriving in time
  double safety_scale = 1.0;    ///< force scale applied by the safety layer [0, 1]
  // transparency (in contact; slave units, see the file comment)
  double slave_depth_m = 0.0;       ///< how deep the slave's tip is in the object [m]
  double master_depth_m = 0.0;      ///< how deep the master is, along the same normal [m]
  double felt_force_n = 0.0;        ///< device force along the contact normal, slave units [N]
  double contact_force_n = 0.0;     ///< |f_e| at the slave [N]
  double continuous_force_n = 0.0;  ///< the device's continuous rating [N] (0: not judged)
  /// The transparency figures of this sample are meaningful: in-process always; over a
  /// network only when a slave sample arrived, its figures paired with the master's at the time
  /// of the command it echoes (both sides at the same moment of the exchange, not a force felt
  /// now against a slave state a round trip old).
  bool transparency_valid = true;
  double aligned_force_n = 0.0;  ///< |device force| of that moment [N] (free space figures)
};

/// A stiffness from the loading phase of the contacts (see the file comment): the least-squares
/// line F = k x + b through its samples. k is the stiffness, b the force already there at zero
/// depth (the body's weight, the force at the touch). Accumulated without allocation.
struct LoadingFit {
  double sw = 0.0, sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;  // weighted sums
  double x_min = 0.0, x_max = 0.0;  ///< depth range of the samples taken [m]
  std::uint64_t n = 0;
  /// A sample weighted by the depth it stands for (the depth gained since the previous one).
  void add(double depth_m, double force_n, double weight) {
    x_min = n ? std::min(x_min, depth_m) : depth_m;
    x_max = n ? std::max(x_max, depth_m) : depth_m;
    sw += weight;
    sx += weight * depth_m;
    sy += weight * force_n;
    sxx += weight * depth_m * depth_m;
    sxy += weight * depth_m * force_n;
    ++n;
  }
  /// k [N/m]; NaN with fewer than 8 samples or a depth range under 20 um.
  double stiffness() const;
  /// b [N]; NaN where stiffness() is.
  double offset() const;
};

/// Accumulated metrics and the online verdict. See the file comment.
class SessionMetrics {
 public:
  explicit SessionMetrics(VerdictParams params = {}) : p_(params) {}
  /// Clears everything.
  void reset();
  /// Adds one cycle. Allocation-free.
  void update(const MetricsSample& s);

  /// Forces the verdict to unstable (e.g. the safety layer cut the run) with `reason`
  /// (a string literal or other storage that outlives this object).
  void mark_unstable(const char* reason, double time_s) {
    set_verdict(Verdict::kUnstable, reason, time_s);
  }
  /// Verdict so far (worst window).
  Verdict verdict() const { return verdict_; }
  /// Reason of the worst verdict ("saturation", "growing oscillation", "energy", ...).
  const char* verdict_reason() const { return reason_; }
  /// Time the verdict first became unstable [s] (negative if never).
  double unstable_since_s() const { return unstable_time_s_; }
  /// True while the newest windows show the energy falling below -energy_limit_j.
  bool energy_growing() const { return energy_growing_; }

  double position_error_rms_m() const;                      ///< RMS |x_m - x_s| [m]
  double position_error_max_m() const { return err_max_; }  ///< max |x_m - x_s| [m]
  double force_error_rms_n() const;                         ///< RMS |F_dev - F_env| in contact [N]
  double contact_time_s() const { return contact_time_; }   ///< [s]
  double energy_j() const { return energy_; }               ///< passivity observer E [J]
  double energy_min_j() const { return energy_min_; }       ///< lowest E seen [J]
  double max_device_force_n() const { return f_dev_max_; }  ///< largest |F_dev| [N]
  double saturated_time_s() const { return saturated_time_; }  ///< time at the limit [s]
  double link_lost_time_s() const { return link_lost_time_; }  ///< time with link_ok false [s]
  std::uint64_t samples() const { return n_; }                 ///< cycles seen
  std::uint64_t oscillating_windows() const { return osc_windows_total_; }  ///< windows
  std::uint64_t nonfinite_samples() const { return nonfinite_; }            ///< NaN/inf cycles
  /// Records the link's losses so far (cumulative counters of the two delay channels or of
  /// the DDS readers): samples sent and lost each way. Allocation-free.
  void set_losses(std::uint64_t forward_sent, std::uint64_t forward_lost,
                  std::uint64_t backward_sent, std::uint64_t backward_lost) {
    fwd_sent_ = forward_sent;
    fwd_lost_ = forward_lost;
    bwd_sent_ = backward_sent;
    bwd_lost_ = backward_lost;
  }
  /// Fraction of master->slave commands lost.
  double forward_loss() const {
    return fwd_sent_ ? static_cast<double>(fwd_lost_) / static_cast<double>(fwd_sent_) : 0.0;
  }
  /// Fraction of slave->master samples lost.
  double backward_loss() const {
    return bwd_sent_ ? static_cast<double>(bwd_lost_) / static_cast<double>(bwd_sent_) : 0.0;
  }
  /// Mean contact force magnitude |F_env| in contact [N].
  double mean_contact_force_n() const;

  // transparency (see the file comment)
  double free_force_mean_n() const;                      ///< [N]
  double free_force_p99_n() const;                       ///< [N] (5 mN resolution)
  double free_force_max_n() const { return free_max_; }  ///< [N]
  double free_time_s() const { return free_time_; }      ///< [s]
  double felt_force_ratio() const;                       ///< sum felt / sum |f_e| [-]
  double felt_force_error_rms_n() const;                 ///< RMS(felt - |f_e|) [N]
  double felt_stiffness_n_per_m() const { return felt_fit_.stiffness(); }
  double environment_stiffness_n_per_m() const { return env_fit_.stiffness(); }
  /// The two loading fits (felt: felt force against the master's depth; environment: |f_e|
  /// against the slave's depth), over the same samples.
  const LoadingFit& felt_fit() const { return felt_fit_; }
  const LoadingFit& environment_fit() const { return env_fit_; }
  /// Which fits took the newest sample: kLoadingEnvironment | kLoadingFelt bits (0: none; the
  /// two fits take the same samples, the bits let a log tell them apart should they differ).
  static constexpr unsigned kLoadingEnvironment = 1, kLoadingFelt = 2;
  unsigned last_sample_loading() const { return last_loading_; }
  /// The deepest the slave's tip went into an object [m] (slave_depth_m), 0 without contact.
  double max_slave_depth_m() const { return max_slave_depth_m_; }
  double stiffness_ratio() const;  ///< felt / environment stiffness [-] (NaN if unknown)
  /// Time the force was above the continuous rating [s], and the peak of its average [N].
  double over_rating_time_s() const { return over_rating_time_; }
  double peak_average_force_n() const { return f_avg_max_; }

  /// The summary as a JSON object ({"verdict":"stable",...}; NaN as null). Allocates.
  nlohmann::ordered_json summary_fields() const;
  /// summary_fields() written compact, e.g. {"verdict":"stable",...}. Allocates.
  std::string summary_json() const;
  /// The transparency figures as a JSON object (NaN as null). Allocates.
  nlohmann::ordered_json transparency_fields() const;
  /// transparency_fields() written compact. Allocates.
  std::string transparency_json() const;

  /// CSV header of the per-cycle log (see docs/control.md for the columns).
  static const char* csv_header();
  /// Formats one log row for `s` (with the current energy, error and verdict) into `buf`;
  /// returns the characters written (no allocation). Columns match csv_header().
  int format_csv_row(const MetricsSample& s, char* buf, std::size_t size) const;

 private:
  void close_window(double end_time_s);
  void update_transparency(const MetricsSample& s);
  void update_loading(const MetricsSample& s);
  void set_verdict(Verdict v, const char* reason, double t);

  VerdictParams p_;
  std::uint64_t n_ = 0;
  std::uint64_t n_err_ = 0;
  double err_sq_ = 0.0, err_max_ = 0.0;
  std::uint64_t n_contact_ = 0;
  double ferr_sq_ = 0.0, fenv_sum_ = 0.0;
  double contact_time_ = 0.0;
  double energy_ = 0.0, energy_min_ = 0.0;
  double f_dev_max_ = 0.0;
  double saturated_time_ = 0.0;
  double link_lost_time_ = 0.0;
  std::uint64_t nonfinite_ = 0;
  std::uint64_t fwd_sent_ = 0, fwd_lost_ = 0, bwd_sent_ = 0, bwd_lost_ = 0;
  double last_error_m_ = 0.0;

  // current window
  double win_start_s_ = 0.0;
  bool win_started_ = false;
  int sign_[3] = {0, 0, 0};
  int crossings_[3] = {0, 0, 0};
  double win_peak_v_ = 0.0;
  std::uint64_t win_samples_ = 0, win_saturated_ = 0;
  double win_energy_start_ = 0.0;
  // window history
  double prev_peak_v_ = 0.0;
  int growth_run_ = 0;
  int osc_run_ = 0;
  int energy_run_ = 0;
  bool energy_growing_ = false;
  std::uint64_t osc_windows_total_ = 0;

  // transparency
  static constexpr int kFreeBins = 2000;  // 5 mN bins up to 10 N (the last holds the rest)
  std::array<std::uint32_t, kFreeBins> free_hist_{};
  std::uint64_t n_free_ = 0;
  double free_sum_ = 0.0, free_max_ = 0.0, free_time_ = 0.0;
  std::uint64_t n_felt_ = 0;
  double felt_sum_ = 0.0, contact_sum_ = 0.0, felt_err_sq_ = 0.0;
  // the loading phase of a contact: a sample each time both the slave's and the master's depth
  // are kLoadingStepM deeper than at the previous sample taken in the contact
  static constexpr double kLoadingStepM = 2e-6;
  LoadingFit felt_fit_, env_fit_;
  double slave_max_depth_m_ = 0.0;   // slave's depth at the last sample taken (0: the surface)
  double master_max_depth_m_ = 0.0;  // the master's
  unsigned last_loading_ = 0;
  double max_slave_depth_m_ = 0.0;
  double f_avg_ = 0.0, f_avg_max_ = 0.0, over_rating_time_ = 0.0;

  Verdict verdict_ = Verdict::kStable;
  const char* reason_ = "";
  double unstable_time_s_ = -1.0;
};

}  // namespace teleop::master
