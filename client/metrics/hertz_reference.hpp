#pragma once
// The physical reference for a session's "stiffness felt": Hertz contact of the scene's elastic
// ball (its material, radius and weight from the scene description) on the rigid floor, pressed
// by the rigid tip (common/sim/hertz.hpp), at the deepest travel the slave's tip reached, and
// its least-squares line over the travel of the session's loading phase (the summary's stiffness
// fits take one sample per 10 um of depth, so the reference is fitted uniformly in travel too).
#include <string>

namespace teleop::master {

struct HertzReference {
  bool valid = false;                       ///< a ball with a material, and a contact
  double travel_m = 0.0;                    ///< the deepest travel of the tip into the ball [m]
  double force_n = 0.0;                     ///< Hertz force at that travel [N]
  double tangent_n_per_m = 0.0;             ///< dF/d(travel) there [N/m]
  double secant_n_per_m = 0.0;              ///< F / travel there [N/m]
  double fit_from_m = 0.0, fit_to_m = 0.0;  ///< travel of the loading phase [m] (0, 0: none)
  double fit_n_per_m = 0.0;  ///< slope of the line fit of F over that travel [N/m] (0: none)
};

/// Hertz for a ball of E [Pa], nu, radius ball_r_m on the floor under weight_n [N] (0: no
/// preload), pressed by a tip of tip_r_m, at travel_m; with fit_from_m < fit_to_m also the line
/// fit over that travel. Invalid for non-positive inputs.
HertzReference hertz_reference(double youngs_modulus_pa, double poisson_ratio, double ball_r_m,
                               double tip_r_m, double weight_n, double travel_m,
                               double fit_from_m = 0.0, double fit_to_m = 0.0);

/// The summary's line ("  hertz ..."): the stiffness felt and the environment's against the
/// line fit over the loading phase (against the tangent where there is no fit); "" when invalid.
std::string hertz_line(const HertzReference& h, double felt_n_per_m, double environment_n_per_m);

}  // namespace teleop::master
