#pragma once
// A deformable ball measured against physics: Hertz contact, Lamb's free vibrations of an
// elastic sphere and the sag under its own weight, each measured by driving the world exactly
// as a session does (world_step with the tip as a kinematic probe). Used by
// `teleop_experiment validate`, `teleop_bench deformable` and the validation tests.
//
// References:
//   - Hertz, sphere on sphere: F = (4/3) E* sqrt(R) d^(3/2), E* = E / (1 - nu^2) for a rigid
//     counterpart; with the ball on a rigid floor pressed by the rigid tip the two contacts are
//     in series (tip-ball 1/R = 1/r_tip + 1/R_ball, ball-floor R = R_ball): the tip's travel is
//     the sum of both indentations at equal force; under gravity the floor contact is preloaded
//     by the weight first.
//   - Lamb (1882): f = eta c_T / (2 pi R), c_T = sqrt(E / (2 rho (1 + nu))). Torsional l = 2:
//     (l - 1) j_l(eta) = eta j_(l+1)(eta), eta = 2.5011 for any nu. Breathing (spheroidal l = 0):
//     eta_P cot(eta_P) = 1 - (eta_P / 2)^2 (c_L / c_T)^2 with eta = eta_P c_L / c_T. Spheroidal
//     l = 2: the root of the coupled free-surface equation (server/deformable/material.hpp).
#include <map>
#include <string>
#include <vector>

#include "server/deformable/deformable.hpp"

namespace teleop::sim::validation {

/// An isotropic linear-elastic material [SI].
struct Material {
  std::string name;
  double youngs_modulus_pa = 0.0;
  double poisson_ratio = 0.0;
  double density_kg_per_m3 = 0.0;
};

constexpr double kBallRadiusM = 0.25;  ///< the paper's ball [m]
constexpr double kTipRadiusM = 0.05;   ///< the slave's tip [m]
/// Support::kHeldCentre holds the nodes within this of the centre (at least the nearest) [m]
constexpr double kHeldRadiusM = 0.025;

/// The project's ball: E = 6000 Pa, nu = 0.3, 2 kg at radius 0.25 m.
Material foam();
/// A silicone-like rubber: E = 50 kPa, nu = 0.45, 1100 kg/m^3.
Material silicone();

/// E* = E / (1 - nu^2) of an elastic body against a rigid one [Pa].
double contact_modulus_pa(const Material& m);
/// Hertz force of one contact [N] at indentation depth_m [m].
double hertz_force_n(double e_star_pa, double r_eff_m, double depth_m);
/// Inverse: the indentation of one contact [m] at force_n [N].
double hertz_depth_m(double e_star_pa, double r_eff_m, double force_n);
/// Tip travel [m] of the ball on a rigid floor pressed by the tip with force_n [N], the floor
/// contact preloaded by preload_n [N] (the weight, or 0).
double hertz_floor_travel_m(const Material& m, double ball_r_m, double tip_r_m, double force_n,
                            double preload_n);
/// Inverse of hertz_floor_travel_m: the tip force [N] at travel_m [m].
double hertz_floor_force_n(const Material& m, double ball_r_m, double tip_r_m, double travel_m,
                           double preload_n);
/// Tip force [N] of the single tip-ball contact (the ball held far from it) at depth_m [m].
double hertz_tip_force_n(const Material& m, double ball_r_m, double tip_r_m, double depth_m);

/// The free-vibration modes of a solid sphere measured here.
enum class LambMode { kS2, kT2, kS0 };
const char* to_string(LambMode mode);
/// Lamb's dimensionless frequency eta of `mode` at Poisson ratio nu
/// (server/deformable/material.hpp).
/// @throws std::domain_error for S2 and S0 with nu outside [0, 0.49].
double lamb_eta(LambMode mode, double nu);
/// Lamb's frequency [Hz] of `mode` for a ball of `radius_m`.
double lamb_frequency_hz(LambMode mode, const Material& m, double radius_m);

/// The parameters of a ball of the material: model and integrator given, geometry at `level`,
/// resting on the floor (its lowest point at z = 0 for the icosphere, the poles for fem), the
/// material's E, nu and density, every other field as a scene file's body of that model gets it
/// (mass-spring: springs derived from the material, springs_from_material, as a scene body that
/// gives youngs_modulus_pa).
deformable::DeformableParams ball_params(deformable::ModelKind model,
                                         deformable::IntegratorKind integrator, int level,
                                         const Material& material);

/// Forces on the tip at the travels asked for.
struct PressResult {
  std::vector<double> travel_m;  ///< as asked [m]
  std::vector<double> force_n;   ///< normal force on the tip there (NaN if not reached) [N]
  double sag_top_m = 0.0;        ///< descent of the top under the weight before the press [m]
  double sag_centre_m = 0.0;     ///< descent of the centre of mass under the weight [m]
  double floor_force_n = 0.0;    ///< the floor's reaction when settled [N]
  int nodes = 0, tets = 0;       ///< the body's nodes (all) and tetrahedra (fem; else 0)
  std::uint64_t faults = 0;      ///< deformable faults during the run
  double step_us = 0.0;          ///< mean wall time of a world step during the press [us]
};

/// How the ball is held while the tip presses it.
enum class Support {
  kFloor,       ///< resting on the rigid floor
  kHeldCentre,  ///< no floor, no gravity: nodes within kHeldRadiusM of the centre held (fem only)
};

/// Presses the ball with the tip (kinematic, straight down at its top, speed_mps) through the
/// travels [m] (ascending), after settling it (dynamic relaxation: velocities scaled by 0.97
/// per 1 ms step for settle_s). gravity: the ball's weight acts (kFloor only). During the press
/// a relaxation of the velocities relative to the mean one (relax_factor per step) keeps it
/// quasi-static without resisting the body's translation, and the body's own drag
/// (mass_damping_per_s) is off: the force measured is the elastic one, not a drag on the ball
/// moving into the floor.
PressResult press_ball(const deformable::DeformableParams& params, Support support, bool gravity,
                       const std::vector<double>& travels_m, double speed_mps, double settle_s,
                       double relax_factor = 0.98);

/// The frequency [Hz] of the body's free vibration (zero gravity, no planes, no damping)
/// started by the velocity field of `mode` (S2: (x, y, -2z); T2: (y z, -x z, 0) / R; S0:
/// (x, y, z), about the centre), from the largest peak of the Hann-windowed spectrum of the
/// mode's coordinate over duration_s, refined by a parabola. Also returns the mean wall time of
/// a step and the body's faults: a run that blew up (explicit Euler, unstable without damping at
/// any step) stops at the fault and returns NaN.
double free_vibration_hz(deformable::DeformableParams params, LambMode mode, double duration_s,
                         double expected_hz, double* step_us = nullptr,
                         std::uint64_t* faults = nullptr);

/// The velocity field that starts `mode` at point p (relative to the centre, in units of the
/// radius): S2 (x, y, -2z), T2 (y z, -x z, 0), S0 (x, y, z).
Eigen::Vector3d lamb_mode_field(LambMode mode, const Eigen::Vector3d& p);

/// The converged CalculiX ball (tests/reference/calculix/ball_reference.csv, see its README):
/// the fine mesh's small-strain (linear elasticity) values, keyed by calculix_key. The file's
/// geometrically nonlinear rows use another material law under large strain and are left out.
/// Empty when the file cannot be read.
std::map<std::string, double> calculix_reference();
/// "material,case,quantity,travel" with the travel in mm as travel_mm_text writes it, e.g.
/// calculix_key("foam", "tip_floor_gravity", "tip_force", 5e-3) for the tip's force [N] at a
/// 5 mm press of the ball resting on the floor under its weight.
std::string calculix_key(const std::string& material, const std::string& case_name,
                         const std::string& quantity, double travel_m);
/// A travel [m] as the CSVs write it in mm ("%g"; empty for travel_m <= 0).
std::string travel_mm_text(double travel_m);

/// The frequency [Hz] of the largest peak of the Hann-windowed spectrum of samples q (period
/// dt_s) between 0.3 and 2.5 times expected_hz, refined by a parabola through its neighbours;
/// NaN when the largest value is on the edge of that range (no vibration in it).
double dominant_frequency_hz(const std::vector<double>& q, double dt_s, double expected_hz);

}  // namespace teleop::sim::validation
