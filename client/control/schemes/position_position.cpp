#include "client/control/schemes/position_position.hpp"

#include "client/control/schemes/laws.hpp"
#include "client/control/tuning.hpp"

namespace teleop::master {

SchemeTraits PositionPositionController::traits(const ControllerParams& /*params*/) {
  SchemeTraits t;
  t.tunable_gains = kTuneMasterStiffness | kTuneMasterDamping | kTuneSlaveStiffness;
  t.position_based = true;
  return t;
}

void PositionPositionController::compute(const DeviceReading& master, const SlaveSample& slave,
                                         double /*dt_s*/, ControlOutput& out) {
  out.force_n = laws::position_position_force(params_.workspace, k_pm_, b_m_, master, slave);
}

}  // namespace teleop::master
