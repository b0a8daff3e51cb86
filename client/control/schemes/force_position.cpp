#include "client/control/schemes/force_position.hpp"

#include "client/control/schemes/laws.hpp"
#include "client/control/tuning.hpp"

namespace teleop::master {

SchemeTraits ForcePositionController::traits(const ControllerParams& /*params*/) {
  SchemeTraits t;
  t.tunable_gains = kTuneForceGain | kTuneMasterDamping | kTuneSlaveStiffness;
  return t;
}

void ForcePositionController::on_activate(const DeviceReading& /*master*/) { damping_share_ = 0.0; }

void ForcePositionController::compute(const DeviceReading& master, const SlaveSample& slave,
                                      double dt_s, ControlOutput& out) {
  damping_share_ = laws::ramp_toward(damping_share_, slave.valid && slave.in_contact ? 1.0 : 0.0,
                                     dt_s / params_.contact_damping_ramp_s);
  out.force_n = laws::force_position_force(params_.workspace, params_.force_gain,
                                           damping_share_ * b_m_, master, slave);
}

}  // namespace teleop::master
