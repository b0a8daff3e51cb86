#include "client/metrics/hertz_reference.hpp"

#include <cmath>
#include <cstdio>

#include "common/sim/hertz.hpp"

namespace teleop::master {

namespace {
/// Slope of the least-squares line through F(x) at n points spread evenly over [from, to].
double line_fit_slope(double es, double ball_r_m, double tip_r_m, double weight_n, double from,
                      double to) {
  constexpr int kPoints = 401;
  double sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
  for (int i = 0; i < kPoints; ++i) {
    const double x = from + (to - from) * i / (kPoints - 1);
    const double f = sim::hertz::floor_force_n(es, ball_r_m, tip_r_m, x, weight_n);
    sx += x;
    sy += f;
    sxx += x * x;
    sxy += x * f;
  }
  return (sxy - sx * sy / kPoints) / (sxx - sx * sx / kPoints);
}
}  // namespace

HertzReference hertz_reference(double youngs_modulus_pa, double poisson_ratio, double ball_r_m,
                               double tip_r_m, double weight_n, double travel_m, double fit_from_m,
                               double fit_to_m) {
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
  if (h.valid && fit_from_m >= 0.0 && fit_to_m > fit_from_m && std::isfinite(fit_to_m)) {
    h.fit_from_m = fit_from_m;
    h.fit_to_m = fit_to_m;
    h.fit_n_per_m = line_fit_slope(es, ball_r_m, tip_r_m, weight_n, fit_from_m, fit_to_m);
  }
  return h;
}

std::string hertz_line(const HertzReference& h, double felt_n_per_m, double environment_n_per_m) {
  if (!h.valid) return "";
  char buf[384];
  int n =
      std::snprintf(buf, sizeof(buf),
                    "  hertz           at the deepest travel %.1f mm: %.2f N, tangent %.0f N/m, "
                    "secant %.0f N/m",
                    h.travel_m * 1e3, h.force_n, h.tangent_n_per_m, h.secant_n_per_m);
  if (h.fit_n_per_m > 0.0) {
    std::snprintf(buf + n, sizeof(buf) - static_cast<std::size_t>(n),
                  "; line fit over the loading phase (%.1f-%.1f mm) %.0f N/m: stiffness felt "
                  "%.2f x, environment %.2f x\n",
                  h.fit_from_m * 1e3, h.fit_to_m * 1e3, h.fit_n_per_m, felt_n_per_m / h.fit_n_per_m,
                  environment_n_per_m / h.fit_n_per_m);
  } else {
    std::snprintf(buf + n, sizeof(buf) - static_cast<std::size_t>(n),
                  "; stiffness felt %.2f x the tangent\n", felt_n_per_m / h.tangent_n_per_m);
  }
  return buf;
}

}  // namespace teleop::master
