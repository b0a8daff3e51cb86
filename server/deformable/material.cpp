// Lamb's roots and the mass-spring springs of a material (material.hpp).
#include "server/deformable/material.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace teleop::sim::deformable {

namespace {

// Bisection of a sign change of f on [a, b].
template <class F>
double bisect(F f, double a, double b) {
  double fa = f(a);
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (a + b);
    const double fm = f(mid);
    if ((fm < 0.0) == (fa < 0.0)) {
      a = mid;
      fa = fm;
    } else {
      b = mid;
    }
  }
  return 0.5 * (a + b);
}

// Spherical Bessel functions j_2 and j_3.
double j2(double x) {
  return (3.0 / (x * x) - 1.0) * std::sin(x) / x - 3.0 * std::cos(x) / (x * x);
}
double j3(double x) {
  return (15.0 / (x * x * x) - 6.0 / x) * std::sin(x) / x -
         (15.0 / (x * x) - 1.0) * std::cos(x) / x;
}

void check_nu(double nu, const char* mode) {
  if (!(nu >= 0.0 && nu <= 0.49)) {
    throw std::domain_error(std::string("Lamb ") + mode + ": Poisson ratio " + std::to_string(nu) +
                            " is outside [0, 0.49]");
  }
}

}  // namespace

double lamb_eta_t2() {
  return bisect([](double x) { return j2(x) - x * j3(x); }, 2.0, 3.0);
}

double lamb_eta_s2(double nu) {
  check_nu(nu, "S2");
  const double ct_over_cl = std::sqrt((1.0 - 2.0 * nu) / (2.0 * (1.0 - nu)));
  auto J = [](double x) { return x * j3(x) / j2(x); };  // x j_3(x) / j_2(x), l = 2
  auto f = [&](double eta) {
    const double xi = eta * ct_over_cl, e2 = eta * eta;
    return 2.0 * (e2 + 4.0 * (J(eta) - 3.0)) * J(xi) - 0.5 * e2 * e2 + 5.0 * e2 +
           (e2 - 16.0) * J(eta);
  };
  // the lowest root: 2.59 at nu = 0 to 2.665 at 0.49, alone in [2.3, 3.0] (j_2 has no zero there)
  return bisect(f, 2.3, 3.0);
}

double lamb_eta_s0(double nu) {
  check_nu(nu, "S0");
  const double ratio2 = 2.0 * (1.0 - nu) / (1.0 - 2.0 * nu);  // (c_L / c_T)^2
  const double xp =
      bisect([&](double x) { return x / std::tan(x) - 1.0 + 0.25 * x * x * ratio2; }, 1.6, 3.1);
  return xp * std::sqrt(ratio2);
}

MassSpringStiffness mass_spring_from_material(double youngs_pa, double nu, double radius_m,
                                              double centre_mass_fraction) {
  auto refuse = [](const std::string& what) {
    throw config::ConfigError("mass-spring from a material: " + what);
  };
  if (!(youngs_pa > 0.0) || !std::isfinite(youngs_pa)) {
    refuse("youngs_modulus_pa " + std::to_string(youngs_pa) + " must be > 0");
  }
  if (!(nu >= 0.0 && nu <= 0.49)) {
    refuse("poisson_ratio " + std::to_string(nu) + " is outside [0, 0.49]");
  }
  if (!(radius_m > 0.0) || !std::isfinite(radius_m)) {
    refuse("radius " + std::to_string(radius_m) + " m must be > 0");
  }
  if (!(centre_mass_fraction > 0.0 && centre_mass_fraction < 1.0)) {
    refuse("centre_mass_fraction " + std::to_string(centre_mass_fraction) + " is outside (0, 1)");
  }
  const double mu = youngs_pa / (2.0 * (1.0 + nu));
  const double eta_t = lamb_eta_t2(), eta_s = lamb_eta_s2(nu);
  const double r = (eta_s / eta_t) * (eta_s / eta_t);
  MassSpringStiffness out;
  out.edge_n_per_m =
      (1.0 - centre_mass_fraction) * eta_t * eta_t * mu * radius_m / (3.0 * std::sqrt(3.0));
  const double membrane = std::sqrt(3.0) * out.edge_n_per_m / 4.0;  // 2-D Lame modulus [N/m]
  out.radial_n_per_m3 = membrane * (24.0 / (4.0 - r) + 4.0 * r - 8.0) / (radius_m * radius_m);
  return out;
}

}  // namespace teleop::sim::deformable
