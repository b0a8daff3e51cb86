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
//     The session verdict is the worst window verdict (unstable latches).
#include <Eigen/Core>
#include <cstdint>
#include <string>

namespace teleop::master {

/// Stability verdict of a run.
enum class Verdict : std::uint8_t { kStable = 0, kOscillating = 1, kUnstable = 2 };
/// "stable" | "oscillating" | "unstable".
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
  int energy_windows = 1;                ///< windows in a row with E < -limit and falling
  double settle_s = 0.0;                 ///< windows ending before this are not judged [s]
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

  /// JSON object with the summary, e.g. {"verdict":"stable",...}. Allocates.
  std::string summary_json() const;

  /// CSV header of the per-cycle log (see docs/control.md for the columns).
  static const char* csv_header();
  /// Formats one log row for `s` (with the current energy, error and verdict) into `buf`;
  /// returns the characters written (no allocation). Columns match csv_header().
  int format_csv_row(const MetricsSample& s, char* buf, std::size_t size) const;

 private:
  void close_window(double end_time_s);
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

  Verdict verdict_ = Verdict::kStable;
  const char* reason_ = "";
  double unstable_time_s_ = -1.0;
};

}  // namespace teleop::master
