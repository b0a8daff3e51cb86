#pragma once
// The position-position scheme, master side (client/control/bilateral_controller.hpp has the base).
//
// position-position (paper Fig. 10): the master feels a spring to the (delayed) slave
//   position and a damper:      F_m = K_pm (x_s' - x_m) - B_m v_m,   x_s' = slave pos. in
//   master frame; the slave is commanded x_c = map(x_m) and tracks it with its own K_ps.
#include "client/control/bilateral_controller.hpp"

namespace teleop::master {

/// Fig. 10: position-position.
class PositionPositionController final : public BilateralController {
 public:
  const char* name() const override { return "position-position"; }
  SchemeId scheme() const override { return SchemeId::kPositionPosition; }
  /// What the shared code asks of it (client/control/scheme_traits.hpp), in its .cpp.
  static SchemeTraits traits(const ControllerParams& params);

 protected:
  void compute(const DeviceReading& master, const SlaveSample& slave, double dt_s,
               ControlOutput& out) override;
};

}  // namespace teleop::master
