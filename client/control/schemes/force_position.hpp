#pragma once
// The force-position scheme, master side (client/control/bilateral_controller.hpp has the base).
//
// force-position (paper Fig. 11): the master sends x_m; the slave returns its contact force
//   f_e (environment on tip); the master renders   F_m = K_f beta R^T f_e - s B_m v_m, the
//   damping share s ramped (contact_damping_ramp_s) to 1 while the slave is in contact and to
//   0 in free space: nothing there for the damper to stabilise, so free motion is not dragged.
//   (The paper writes F_m = -K_f f_e with f_e the force the slave exerts on the environment;
//   ours is the reaction, hence the sign.)

#include "client/control/bilateral_controller.hpp"

namespace teleop::master {

/// Fig. 11: force-position.
class ForcePositionController final : public BilateralController {
 public:
  const char* name() const override { return "force-position"; }
  SchemeId scheme() const override { return SchemeId::kForcePosition; }
  /// What the shared code asks of it (client/control/scheme_traits.hpp), in its .cpp.
  static SchemeTraits traits(const ControllerParams& params);
  double environment_force_gain() const override { return params_.force_gain; }

 protected:
  void on_activate(const DeviceReading& master) override;
  void compute(const DeviceReading& master, const SlaveSample& slave, double dt_s,
               ControlOutput& out) override;

 private:
  double damping_share_ = 0.0;  // B_m's share now: 1 in contact, 0 in free space, ramped
};

}  // namespace teleop::master
