#pragma once
// What the deformable models derive from a material (Young's modulus E, Poisson ratio nu; the
// mass or density is the body's): Lamb's free-vibration roots of an elastic sphere, and the
// mass-spring model's springs chosen so that its ball has Lamb's two lowest frequencies
// (docs/deformable.md, "Mass-spring from a material").
//
// Lamb (1882), solid sphere of radius R, shear wave speed c_T = sqrt(E / (2 rho (1 + nu))),
// longitudinal c_L: f = eta c_T / (2 pi R), with eta the root of
//   - torsional l = 2 (T2): (l - 1) j_l(eta) = eta j_(l+1)(eta), eta = 2.5011 for any nu;
//   - spheroidal l = 2 (S2): the free-surface equation of the coupled spheroidal modes, with
//     xi = eta c_T / c_L and J(x) = x j_(l+1)(x) / j_l(x):
//       2 [eta^2 + (l-1)(l+2)(J(eta) - (l+1))] J(xi) - eta^4 / 2 + (l-1)(2l+1) eta^2
//         + [eta^2 - 2 l (l-1)(l+2)] J(eta) = 0;
//   - breathing l = 0 (S0): xi cot(xi) = 1 - (xi / 2)^2 (c_L / c_T)^2, eta = xi c_L / c_T.
#include "common/config/config.hpp"

namespace teleop::sim::deformable {

/// Lamb's root of the torsional mode T2 (independent of nu): 2.5011.
double lamb_eta_t2();
/// Lamb's root of the spheroidal mode S2 at Poisson ratio nu in [0, 0.49] (2.592 at 0, 2.646 at
/// 0.3, 2.662 at 0.45). @throws std::domain_error outside that range.
double lamb_eta_s2(double nu);
/// Lamb's root of the breathing mode S0 at nu in [0, 0.49]. @throws std::domain_error outside.
double lamb_eta_s0(double nu);

/// The two spring fields of model mass_spring.
struct MassSpringStiffness {
  double edge_n_per_m = 0.0;     ///< each edge spring (edge_stiffness_n_per_m) [N/m]
  double radial_n_per_m3 = 0.0;  ///< radial springs per node area (radial_stiffness_n_per_m3)
};

/// The mass-spring ball of radius radius_m whose lowest torsional (T2) and spheroidal (S2)
/// frequencies are Lamb's for a material of youngs_pa and nu, with centre_mass_fraction of its
/// mass on the centre node. The surface is taken as a membrane (an equilateral lattice of springs
/// k has 2-D Lame moduli lambda = mu = sqrt(3) k / 4) on a radial foundation (pressure k_r per
/// metre of radial displacement) carrying (1 - f_c) of the mass; its degree-2 modes give
///   k   = (1 - f_c) eta_T2^2 mu R / (3 sqrt(3)),      mu = E / (2 (1 + nu)),
///   k_r = (sqrt(3) k / 4) [24 / (4 - r) + 4 r - 8] / R^2,   r = (eta_S2 / eta_T2)^2.
/// The density cancels (both sides scale with it); the mesh level does not enter (the lattice's
/// membrane modulus and the per-area radial springs do not depend on it).
/// @throws config::ConfigError when an argument is out of range (E > 0, nu in [0, 0.49],
/// R > 0, f_c in (0, 1)).
MassSpringStiffness mass_spring_from_material(double youngs_pa, double nu, double radius_m,
                                              double centre_mass_fraction);

}  // namespace teleop::sim::deformable
