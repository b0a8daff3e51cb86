#pragma once
// Analytic delay margin of the linearised bilateral loop (one axis, permanent contact).
//
//   master + hand:  G_m(s) = 1 / (M s^2 + B s + K)      M = m_d + m_h, B = b_d + B_h + B_m,
//                                                       K = K_h (+ K_pm for position-position)
//   slave + env:    G_s(s) = (K_ps + B_ps s) / (m_s s^2 + (B_ps + b_s + B_e) s + K_ps + K_e)
//   position-position:  F_m = K_pm x_s(t - T)    -> 1 - L(s) e^{-2sT} = 0, L = K_pm G_m G_s
//   force-position:     F_m = -K_f beta f       -> 1 + L(s) e^{-2sT} = 0,
//                       L = alpha beta K_f (K_e + B_e s) G_m G_s
// Written as 1 + L_n(s) e^{-s tau} = 0 (L_n = -L for position-position, tau = 2T round trip),
// the loop, stable at zero delay, first loses stability at the smallest tau for which
// L_n(jw) e^{-jw tau} = -1: at a gain crossover w_c (|L_n(jw_c)| = 1) with
// tau = PM(w_c) / w_c, PM = pi + arg L_n(jw_c) in [0, 2 pi) (Astrom & Murray, delay margin).
// No crossover (|L_n| < 1 for all w) means stable for every delay (small-gain).
// See docs/control.md for the derivation.
#include <complex>
#include <limits>

namespace teleop::master {

/// Linear one-axis model of the loop. Units as named.
struct LoopModel {
  bool position_position = true;          ///< true: position-position; false: force-position
  double master_mass_kg = 0.5;            ///< M = device + hand mass [kg]
  double master_damping_ns_per_m = 8.5;   ///< b_d + B_h + B_m [N s/m]
  double hand_stiffness_n_per_m = 300.0;  ///< K_h [N/m]
  double master_gain_n_per_m = 400.0;     ///< K_pm [N/m] (position-position)
  double force_gain = 1.0;                ///< alpha beta K_f [-] (force-position)
  double slave_mass_kg = 0.2;             ///< m_s [kg]
  double slave_kp_n_per_m = 400.0;        ///< K_ps [N/m]
  double slave_kd_ns_per_m = 12.0;        ///< B_ps [N s/m]
  double slave_damping_ns_per_m = 0.5;    ///< b_s [N s/m]
  double env_stiffness_n_per_m = 2.0e4;   ///< K_e [N/m]
  double env_damping_ns_per_m = 50.0;     ///< B_e [N s/m]
};

/// L_n(jw): the loop gain in negative-feedback form (see the file comment).
std::complex<double> loop_gain(const LoopModel& m, double w_radps);

/// Result of the delay-margin computation.
struct DelayMargin {
  double one_way_s = std::numeric_limits<double>::infinity();  ///< T* = tau* / 2 [s]
  double crossover_radps = 0.0;   ///< w_c of the limiting crossover [rad/s] (0: none)
  double phase_margin_rad = 0.0;  ///< PM at that crossover [rad]
  double dc_gain = 0.0;           ///< |L_n(0)|
};

/// Scans w in [w_min, w_max] (log grid, bisection at each crossing) and returns the
/// smallest delay margin over all crossovers.
DelayMargin delay_margin(const LoopModel& m, double w_min_radps = 0.01, double w_max_radps = 1.0e4);

/// Margin of a task that moves both in free space and in contact: the smaller of the margin
/// in contact (m as given) and in free motion (m with K_e = B_e = 0).
DelayMargin task_delay_margin(const LoopModel& m);

}  // namespace teleop::master
