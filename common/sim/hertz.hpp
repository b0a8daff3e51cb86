#pragma once
// Hertz contact of an elastic ball against rigid bodies: the reference the FEM is validated
// against (server/world/physics_validation.hpp) and the stiffness a session's "stiffness felt"
// is compared with (the master's summary).
//
//   one contact: F = (4/3) E* sqrt(R) d^(3/2), E* = E / (1 - nu^2) against a rigid body, R the
//   effective radius (1/R = 1/R_1 + 1/R_2);
//   a ball on a rigid floor pressed from above by a rigid tip: the two contacts in series, the
//   tip's travel the sum of both indentations at equal force, the floor contact preloaded by
//   the ball's weight first.
namespace teleop::sim::hertz {

/// E* = E / (1 - nu^2) of an elastic body against a rigid one [Pa].
double contact_modulus_pa(double youngs_modulus_pa, double poisson_ratio);
/// Force of one contact [N] at indentation depth_m [m] (0 for depth <= 0).
double force_n(double e_star_pa, double r_eff_m, double depth_m);
/// Inverse of force_n: the indentation [m] at force_n [N].
double depth_m(double e_star_pa, double r_eff_m, double force_n);
/// Tip travel [m] of the ball (radius ball_r_m) on a rigid floor pressed by a rigid tip (radius
/// tip_r_m) with force_n [N], the floor contact preloaded by preload_n [N].
double floor_travel_m(double e_star_pa, double ball_r_m, double tip_r_m, double force_n,
                      double preload_n);
/// Inverse of floor_travel_m: the tip's force [N] at travel_m [m].
double floor_force_n(double e_star_pa, double ball_r_m, double tip_r_m, double travel_m,
                     double preload_n);
/// dF/d(travel) of floor_force_n at travel_m [N/m]: the tangent stiffness the tip meets there.
double floor_tangent_n_per_m(double e_star_pa, double ball_r_m, double tip_r_m, double travel_m,
                             double preload_n);

}  // namespace teleop::sim::hertz
