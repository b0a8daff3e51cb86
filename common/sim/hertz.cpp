#include "common/sim/hertz.hpp"

#include <cmath>

namespace teleop::sim::hertz {

double contact_modulus_pa(double youngs_modulus_pa, double poisson_ratio) {
  return youngs_modulus_pa / (1.0 - poisson_ratio * poisson_ratio);
}

double force_n(double e_star_pa, double r_eff_m, double depth_m) {
  if (!(depth_m > 0.0)) return 0.0;
  return 4.0 / 3.0 * e_star_pa * std::sqrt(r_eff_m) * std::pow(depth_m, 1.5);
}

double depth_m(double e_star_pa, double r_eff_m, double force_n) {
  if (!(force_n > 0.0)) return 0.0;
  return std::pow(force_n / (4.0 / 3.0 * e_star_pa * std::sqrt(r_eff_m)), 2.0 / 3.0);
}

double floor_travel_m(double e_star_pa, double ball_r_m, double tip_r_m, double force_n,
                      double preload_n) {
  const double r_tip = 1.0 / (1.0 / tip_r_m + 1.0 / ball_r_m);
  return depth_m(e_star_pa, r_tip, force_n) + depth_m(e_star_pa, ball_r_m, force_n + preload_n) -
         depth_m(e_star_pa, ball_r_m, preload_n);
}

double floor_force_n(double e_star_pa, double ball_r_m, double tip_r_m, double travel_m,
                     double preload_n) {
  if (!(travel_m > 0.0)) return 0.0;
  double lo = 0.0, hi = 1.0;
  while (floor_travel_m(e_star_pa, ball_r_m, tip_r_m, hi, preload_n) < travel_m && hi < 1e9) {
    hi *= 2;
  }
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    (floor_travel_m(e_star_pa, ball_r_m, tip_r_m, mid, preload_n) < travel_m ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double floor_tangent_n_per_m(double e_star_pa, double ball_r_m, double tip_r_m, double travel_m,
                             double preload_n) {
  // the compliances of the two contacts add: d(travel)/dF = dd_tip/dF + dd_floor/dF, with
  // dd/dF = 2 d / (3 F) for one Hertz contact
  const double f = floor_force_n(e_star_pa, ball_r_m, tip_r_m, travel_m, preload_n);
  if (!(f > 0.0)) return 0.0;
  const double r_tip = 1.0 / (1.0 / tip_r_m + 1.0 / ball_r_m);
  const double c_tip = 2.0 * depth_m(e_star_pa, r_tip, f) / (3.0 * f);
  const double floor_f = f + preload_n;
  const double c_floor = 2.0 * depth_m(e_star_pa, ball_r_m, floor_f) / (3.0 * floor_f);
  return 1.0 / (c_tip + c_floor);
}

}  // namespace teleop::sim::hertz
