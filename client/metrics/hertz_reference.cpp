#include "client/metrics/hertz_reference.hpp"

#include <cmath>
#include <cstdio>

#include "common/sim/hertz.hpp"

namespace teleop::master {

HertzReference hertz_reference(double youngs_modulus_pa, double poisson_ratio, double ball_r_m,
                               double tip_r_m, double weight_n, double travel_m) {
  HertzReference h;
  if (!(youngs_modulus_pa > 0.0) || !(poisson_ratio >= 0.0 && poisson_ratio < 0.5) ||
      !(ball_r_m > 0.0) || !(tip_r_m > 0.0) || !(weight_n >= 0.0) || !(travel_m > 0.0) ||
      !std::isfinite(travel_m)) {
    return h;
  }
  const double es = sim::hertz::contact_modulus_pa(youngs_modulus_pa, poisson_ratio);
  h.travel_m = travel_m;
  h.force_n = sim::hertz::floor_force_n(es, ball_r_m, tip_r_m, travel_m, weight_n);
  h.tangent_n_per_m = sim::hertz::floor_tangent_n_per_m(es, ball_r_m, tip_r_m, travel_m, weight_n);
  h.secant_n_per_m = h.force_n / travel_m;
  h.valid = h.force_n > 0.0 && h.tangent_n_per_m > 0.0;
  return h;
}

std::string hertz_line(const HertzReference& h, double felt_n_per_m) {
  if (!h.valid) return "";
  char buf[256];
  std::snprintf(buf, sizeof(buf),
                "  hertz           at the deepest travel %.1f mm: %.2f N, tangent %.0f N/m, secant "
                "%.0f N/m; stiffness felt %.2f x the tangent\n",
                h.travel_m * 1e3, h.force_n, h.tangent_n_per_m, h.secant_n_per_m,
                felt_n_per_m / h.tangent_n_per_m);
  return buf;
}

}  // namespace teleop::master
