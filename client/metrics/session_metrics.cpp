#include "client/metrics/session_metrics.hpp"

#include "common/util/json.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace teleop::master {

const char* verdict_name(Verdict v) {
  switch (v) {
    case Verdict::kStable:
      return "stable";
    case Verdict::kOscillating:
      return "oscillating";
    case Verdict::kUnstable:
      return "unstable";
    case Verdict::kOutOfSpec:
      return "out-of-spec";
  }
  return "?";
}

namespace {
/// Severity: stable < oscillating < out of spec < unstable.
int rank(Verdict v) {
  switch (v) {
    case Verdict::kStable:
      return 0;
    case Verdict::kOscillating:
      return 1;
    case Verdict::kOutOfSpec:
      return 2;
    case Verdict::kUnstable:
      return 3;
  }
  return 3;
}
}  // namespace

double LoadingFit::stiffness() const {
  if (n < 8 || x_max - x_min < 2e-5) return std::nan("");
  const double var = sxx - sx * sx / sw;
  return var > 0.0 ? (sxy - sx * sy / sw) / var : std::nan("");
}

double LoadingFit::offset() const {
  const double k = stiffness();
  return std::isfinite(k) ? (sy - k * sx) / sw : std::nan("");
}

void SessionMetrics::reset() {
  const VerdictParams p = p_;
  *this = SessionMetrics(p);
}

void SessionMetrics::set_verdict(Verdict v, const char* reason, double t) {
  if (rank(v) <= rank(verdict_)) return;
  verdict_ = v;
  reason_ = reason;
  if (v == Verdict::kUnstable && unstable_time_s_ < 0.0) unstable_time_s_ = t;
}

void SessionMetrics::update(const MetricsSample& s) {
  ++n_;
  const double dt = s.dt_s;
  if (!win_started_) {
    win_started_ = true;
    win_start_s_ = s.time_s;
    win_energy_start_ = energy_;
  }
  const bool finite = s.master_position_m.allFinite() && s.slave_position_m.allFinite() &&
                      s.master_velocity_mps.allFinite() && s.device_force_n.allFinite() &&
                      s.environment_force_n.allFinite();
  if (!finite) {
    ++nonfinite_;
    set_verdict(Verdict::kUnstable, "non-finite value", s.time_s);
    return;
  }

  // tracking error
  if (s.have_slave) {
    const double e = (s.master_position_m - s.slave_position_m).norm();
    last_error_m_ = e;
    err_sq_ += e * e;
    err_max_ = std::max(err_max_, e);
    ++n_err_;
  }
  // force fidelity in contact
  if (s.in_contact) {
    ++n_contact_;
    contact_time_ += dt;
    ferr_sq_ += (s.device_force_n - s.environment_force_n).squaredNorm();
    fenv_sum_ += s.environment_force_n.norm();
  }
  if (!s.link_ok) link_lost_time_ += dt;
  update_transparency(s);

  // passivity observer of the master port: power from the operator into the teleoperator
  energy_ += -dt * s.device_force_n.dot(s.master_velocity_mps);
  energy_min_ = std::min(energy_min_, energy_);

  const double fn = s.device_force_n.norm();
  f_dev_max_ = std::max(f_dev_max_, fn);
  const bool sat = fn >= 0.99 * s.force_limit_n;
  if (sat) saturated_time_ += dt;

  // window statistics: zero crossings with hysteresis, peak speed, saturation
  ++win_samples_;
  if (sat) ++win_saturated_;
  for (int i = 0; i < 3; ++i) {
    const double v = s.master_velocity_mps[i];
    const int sg = v > p_.velocity_threshold_mps ? 1 : (v < -p_.velocity_threshold_mps ? -1 : 0);
    if (sg != 0) {
      if (sign_[i] != 0 && sg != sign_[i]) ++crossings_[i];
      sign_[i] = sg;
    }
  }
  win_peak_v_ = std::max(win_peak_v_, s.master_velocity_mps.cwiseAbs().maxCoeff());

  if (s.time_s + 0.5 * dt - win_start_s_ >= p_.window_s) {
    close_window(s.time_s);
    win_start_s_ = s.time_s + dt;
    win_energy_start_ = energy_;
  }
}

void SessionMetrics::update_loading(const MetricsSample& s) {
  // both sides press in: the slave and the master (at the moment of the exchange) each deeper
  // than at the previous sample taken in this contact
  if (s.slave_depth_m < slave_max_depth_m_ + kLoadingStepM ||
      s.master_depth_m < master_max_depth_m_ + kLoadingStepM) {
    return;
  }
  env_fit_.add(s.slave_depth_m, s.contact_force_n, s.slave_depth_m - slave_max_depth_m_);
  felt_fit_.add(s.master_depth_m, s.felt_force_n, s.master_depth_m - master_max_depth_m_);
  slave_max_depth_m_ = s.slave_depth_m;
  master_max_depth_m_ = s.master_depth_m;
  last_loading_ = kLoadingEnvironment | kLoadingFelt;
}

void SessionMetrics::update_transparency(const MetricsSample& s) {
  const double dt = s.dt_s;
  const double fn = s.device_force_n.norm();
  const double fa = s.aligned_force_n;
  last_loading_ = 0;
  if (!s.in_contact || s.slave_depth_m <= 0.0) {  // the contact ended: the next loads anew
    slave_max_depth_m_ = master_max_depth_m_ = 0.0;
  }
  if (s.transparency_valid && !s.in_contact && s.link_ok && s.have_slave) {
    ++n_free_;
    free_sum_ += fa;
    free_max_ = std::max(free_max_, fa);
    free_time_ += dt;
    ++free_hist_[static_cast<std::size_t>(std::min(kFreeBins - 1.0, std::floor(fa / 0.005)))];
  }
  if (s.transparency_valid && s.in_contact && s.contact_force_n > 0.0) {
    ++n_felt_;
    felt_sum_ += s.felt_force_n;
    contact_sum_ += s.contact_force_n;
    felt_err_sq_ += (s.felt_force_n - s.contact_force_n) * (s.felt_force_n - s.contact_force_n);
    if (s.slave_depth_m > 0.0) {
      max_slave_depth_m_ = std::max(max_slave_depth_m_, s.slave_depth_m);
      update_loading(s);
    }
  }
  // the device's continuous rating, judged as its thermal model does
  if (s.continuous_force_n > 0.0) {
    f_avg_ += std::min(1.0, dt / std::max(p_.spec_tau_s, 1e-9)) * (fn - f_avg_);
    f_avg_max_ = std::max(f_avg_max_, f_avg_);
    if (fn > s.continuous_force_n) over_rating_time_ += dt;
    if (f_avg_ > s.continuous_force_n || over_rating_time_ > p_.spec_time_s) {
      set_verdict(Verdict::kOutOfSpec, "force above the device's continuous rating", s.time_s);
    }
  }
}

double SessionMetrics::free_force_mean_n() const {
  return n_free_ ? free_sum_ / static_cast<double>(n_free_) : std::nan("");
}

double SessionMetrics::free_force_p99_n() const {
  if (n_free_ == 0) return std::nan("");
  const auto target = static_cast<std::uint64_t>(std::ceil(0.99 * static_cast<double>(n_free_)));
  std::uint64_t seen = 0;
  for (int i = 0; i < kFreeBins; ++i) {
    seen += free_hist_[static_cast<std::size_t>(i)];
    if (seen >= target) return std::min(free_max_, 0.005 * (i + 1));
  }
  return free_max_;
}

double SessionMetrics::felt_force_ratio() const {
  return contact_sum_ > 0.0 ? felt_sum_ / contact_sum_ : std::nan("");
}

double SessionMetrics::felt_force_error_rms_n() const {
  return n_felt_ ? std::sqrt(felt_err_sq_ / static_cast<double>(n_felt_)) : std::nan("");
}

double SessionMetrics::stiffness_ratio() const {
  const double e = environment_stiffness_n_per_m();
  return e > 0.0 ? felt_stiffness_n_per_m() / e : std::nan("");
}

void SessionMetrics::close_window(double end_time_s) {
  const int crossings = std::max({crossings_[0], crossings_[1], crossings_[2]});
  const bool osc = crossings >= p_.min_crossings;
  const bool judged = end_time_s >= p_.settle_s;
  const double sat_fraction =
      win_samples_ ? static_cast<double>(win_saturated_) / static_cast<double>(win_samples_) : 0.0;

  // growth of the oscillation amplitude
  if (osc && prev_peak_v_ > 0.0 && win_peak_v_ > p_.growth_ratio * prev_peak_v_) {
    ++growth_run_;
  } else {
    growth_run_ = 0;
  }
  // energy generated by the teleoperator, still being generated
  const bool falling = energy_ < win_energy_start_ - 1e-6;
  energy_run_ = (falling && energy_ < -p_.energy_limit_j) ? energy_run_ + 1 : 0;
  energy_growing_ = energy_run_ >= p_.energy_windows;
  osc_run_ = osc ? osc_run_ + 1 : 0;
  if (osc) ++osc_windows_total_;

  if (judged) {
    if (sat_fraction > p_.saturation_fraction) {
      set_verdict(Verdict::kUnstable, "force saturation", end_time_s);
    } else if (growth_run_ >= p_.growth_windows) {
      set_verdict(Verdict::kUnstable, "growing oscillation", end_time_s);
    } else if (energy_run_ >= p_.energy_windows) {
      set_verdict(Verdict::kUnstable, "energy generated", end_time_s);
    } else if (osc_run_ >= p_.sustain_windows) {
      set_verdict(Verdict::kOscillating, "sustained oscillation", end_time_s);
    }
  }

  prev_peak_v_ = win_peak_v_;
  win_peak_v_ = 0.0;
  win_samples_ = win_saturated_ = 0;
  crossings_[0] = crossings_[1] = crossings_[2] = 0;
}

double SessionMetrics::position_error_rms_m() const {
  return n_err_ ? std::sqrt(err_sq_ / static_cast<double>(n_err_)) : 0.0;
}

double SessionMetrics::force_error_rms_n() const {
  return n_contact_ ? std::sqrt(ferr_sq_ / static_cast<double>(n_contact_)) : 0.0;
}

double SessionMetrics::mean_contact_force_n() const {
  return n_contact_ ? fenv_sum_ / static_cast<double>(n_contact_) : 0.0;
}

OrderedJson SessionMetrics::transparency_fields() const {
  const double nan = std::nan("");
  OrderedJson o;
  o["free_force_mean_n"] = json_number(free_force_mean_n());
  o["free_force_p99_n"] = json_number(free_force_p99_n());
  o["free_force_max_n"] = json_number(n_free_ ? free_max_ : nan);
  o["free_time_s"] = json_number(free_time_);
  o["felt_force_ratio"] = json_number(felt_force_ratio());
  o["felt_force_error_rms_n"] = json_number(felt_force_error_rms_n());
  o["felt_stiffness_n_per_m"] = json_number(felt_stiffness_n_per_m());
  o["felt_offset_n"] = json_number(felt_fit_.offset());
  o["environment_stiffness_n_per_m"] = json_number(environment_stiffness_n_per_m());
  o["environment_offset_n"] = json_number(env_fit_.offset());
  o["loading_samples"] = json_number(static_cast<double>(env_fit_.n));
  o["loading_depth_min_m"] = json_number(env_fit_.n ? env_fit_.x_min : nan);
  o["loading_depth_max_m"] = json_number(env_fit_.n ? env_fit_.x_max : nan);
  o["stiffness_ratio"] = json_number(stiffness_ratio());
  o["position_error_rms_m"] = json_number(position_error_rms_m());
  o["over_rating_time_s"] = json_number(over_rating_time_);
  o["peak_average_force_n"] = json_number(f_avg_max_);
  return o;
}

std::string SessionMetrics::transparency_json() const {
  return json_compact(transparency_fields());
}

OrderedJson SessionMetrics::summary_fields() const {
  OrderedJson o;
  o["verdict"] = verdict_name(verdict_);
  o["verdict_reason"] = reason_ ? reason_ : "";
  o["unstable_since_s"] = json_number(unstable_time_s_);
  o["position_error_rms_m"] = json_number(position_error_rms_m());
  o["position_error_max_m"] = json_number(err_max_);
  o["force_error_rms_n"] = json_number(force_error_rms_n());
  o["mean_contact_force_n"] = json_number(mean_contact_force_n());
  o["contact_time_s"] = json_number(contact_time_);
  o["energy_j"] = json_number(energy_);
  o["energy_min_j"] = json_number(energy_min_);
  o["max_device_force_n"] = json_number(f_dev_max_);
  o["saturated_time_s"] = json_number(saturated_time_);
  o["link_lost_time_s"] = json_number(link_lost_time_);
  o["oscillating_windows"] = osc_windows_total_;
  o["samples"] = n_;
  o["nonfinite_samples"] = nonfinite_;
  o["forward_loss"] = json_number(forward_loss());
  o["backward_loss"] = json_number(backward_loss());
  return o;
}

std::string SessionMetrics::summary_json() const { return json_compact(summary_fields()); }

const char* SessionMetrics::csv_header() {
  return "time_s,xm_x_m,xm_y_m,xm_z_m,xs_x_m,xs_y_m,xs_z_m,vm_x_mps,vm_y_mps,vm_z_mps,"
         "fdev_x_n,fdev_y_n,fdev_z_n,fenv_x_n,fenv_y_n,fenv_z_n,in_contact,link_ok,"
         "safety_scale,energy_j,position_error_m,verdict";
}

int SessionMetrics::format_csv_row(const MetricsSample& s, char* buf, std::size_t size) const {
  const auto& a = s.master_position_m;
  const auto& b = s.slave_position_m;
  const auto& v = s.master_velocity_mps;
  const auto& f = s.device_force_n;
  const auto& e = s.environment_force_n;
  return std::snprintf(buf, size,
                       "%.6f,%.7g,%.7g,%.7g,%.7g,%.7g,%.7g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,"
                       "%.6g,%.6g,%d,%d,%.4g,%.7g,%.6g,%d",
                       s.time_s, a.x(), a.y(), a.z(), b.x(), b.y(), b.z(), v.x(), v.y(), v.z(),
                       f.x(), f.y(), f.z(), e.x(), e.y(), e.z(), s.in_contact ? 1 : 0,
                       s.link_ok ? 1 : 0, s.safety_scale, energy_, last_error_m_,
                       static_cast<int>(verdict_));
}

}  // namespace teleop::master
