#include "client/control/schemes/position_position.hpp"

#include "client/control/schemes/laws.hpp"

namespace teleop::master {

void PositionPositionController::compute(const DeviceReading& master, const SlaveSample& slave,
                                         double /*dt_s*/, ControlOutput& out) {
  out.force_n = laws::position_position_force(params_.workspace, k_pm_, b_m_, master, slave);
}

}  // namespace teleop::master
