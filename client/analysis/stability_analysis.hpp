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

/// One gain crossover w_c (|L_n(jw_c)| = 1) and the round-trip delays at which a root pair
/// crosses the imaginary axis there: tau_n = (PM + 2 pi n) / w_c, n = 0, 1, ...
/// The crossing is destabilising where |L_n| falls through 1 as w grows (roots move into the
/// right half-plane) and stabilising where it rises through 1 (Cooke & van den Driessche 1986:
/// sign of d/dw (1 - |L_n|^2)).
struct DelayCrossing {
  double w_radps = 0.0;             ///< crossover frequency [rad/s]
  double first_round_trip_s = 0.0;  ///< tau_0 = PM / w_c [s]
  bool destabilizing = true;        ///< direction of the root crossing
};

/// All crossovers of a loop (at most kMax; scan as delay_margin()).
struct DelayCrossings {
  static constexpr int kMax = 16;
  DelayCrossing items[kMax];
  int count = 0;
};
DelayCrossings delay_crossings(const LoopModel& m, double w_min_radps = 0.01,
                               double w_max_radps = 1.0e4);

/// Exact delay stability of the linear loop (stable at zero delay assumed): counts the root
/// pairs that crossed into the right half-plane for round-trip delays below 2 T. Captures
/// stability switches (a loop unstable at 50 ms may be stable again at 100 ms).
bool stable_at(const DelayCrossings& c, double one_way_s);
/// stable_at() for a task in contact and in free motion (both must be stable).
bool task_stable_at(const LoopModel& m, double one_way_s);

/// Margin of a task that moves both in free space and in contact: the smaller of the margin
/// in contact (m as given) and in free motion (m with K_e = B_e = 0).
DelayMargin task_delay_margin(const LoopModel& m);

}  // namespace teleop::master
