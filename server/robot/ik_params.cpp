#include "server/robot/ik_params.hpp"

#include <cmath>

namespace teleop::sim::robot {

using config::FieldParam;
using P = IkParams;

const std::vector<FieldParam<P>>& ik_field_params() {
  static const std::vector<FieldParam<P>> t = {
      {.key = "gain_per_s",
       .unit = "1/s",
       .help = "resolved-rate IK: task-space error feedback gain (at least 1: at 0 the robot never "
               "follows; the physics rate must keep h g below 2, checked at load)",
       .lo = kMinIkGainPerS,
       .hi = 1000.0,
       .number = TELEOP_FIELD(P, gain_per_s)},
      {.key = "orientation_weight_m",
       .unit = "m",
       .help = "length that weights the angular rows against the linear ones",
       .hi = 10.0,
       .number = TELEOP_FIELD(P, orientation_weight_m)},
      {.key = "damping_max_m",
       .unit = "m",
       .help = "largest damped-least-squares damping lambda",
       .hi = 10.0,
       .number = TELEOP_FIELD(P, damping_max_m)},
      {.key = "singular_threshold_m",
       .unit = "m",
       .help = "the damping starts when the smallest singular value falls below this",
       .lo = 1e-6,
       .hi = 10.0,
       .number = TELEOP_FIELD(P, singular_threshold_m)},
      {.key = "limit_margin_deg",
       .unit = "deg",
       .help = "the joint reference stays this far inside the joint limits",
       .hi = 30.0,
       .scale = M_PI / 180.0,
       .number = TELEOP_FIELD(P, limit_margin_rad)},
      {.key = "max_tip_speed_mps",
       .unit = "m/s",
       .help = "clamp of the commanded tip speed",
       .lo = 1e-3,
       .hi = 100.0,
       .number = TELEOP_FIELD(P, max_tip_speed_mps)},
      {.key = "max_tip_angular_speed_radps",
       .unit = "rad/s",
       .help = "clamp of the commanded angular speed",
       .lo = 1e-3,
       .hi = 100.0,
       .number = TELEOP_FIELD(P, max_tip_angular_speed_radps)},
      {.key = "friction_compensation",
       .unit = "-",
       .help = "fraction of the model's joint friction fed forward",
       .hi = 1.0,
       .number = TELEOP_FIELD(P, friction_compensation)},
      {.key = "friction_velocity_radps",
       .unit = "rad/s",
       .help = "smoothing speed of the Coulomb feed-forward",
       .lo = 1e-6,
       .hi = 10.0,
       .number = TELEOP_FIELD(P, friction_velocity_radps)},
  };
  return t;
}

}  // namespace teleop::sim::robot
