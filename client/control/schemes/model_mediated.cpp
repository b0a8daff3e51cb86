#include "client/control/schemes/model_mediated.hpp"

#include <algorithm>
#include <cmath>

#include "client/control/schemes/laws.hpp"
#include "client/control/tuning.hpp"

namespace teleop::master {

SchemeTraits ModelMediatedController::traits(const ControllerParams& /*params*/) {
  SchemeTraits t;
  // the force is the local model's: neither K_pm nor K_f
  t.tunable_gains = kTuneMasterDamping | kTuneSlaveStiffness;
  // its force loop closes at the master, not across the delay: stable at every delay
  t.passive_by_design = true;
  t.linear_loop_model = false;
  // it renders from its local model at 4 kHz and sends positions at 1 kHz
  t.default_rate_hz = 4000.0;
  t.default_command_rate_hz = 1000.0;
  return t;
}

const std::vector<ControllerParam>& ModelMediatedController::parameters() {
  using P = ControllerParams;
  static const std::vector<ControllerParam> table = {
      {.key = "mmt_blend_s",
       .unit = "s",
       .help = "time constant of the blend toward each new model",
       .field = &P::mmt_blend_s,
       .lo = 1e-4,
       .hi = 1.0},
      {.key = "mmt_energy_rate_w",
       .unit = "W",
       .help = "energy model updates may add at the master per second",
       .field = &P::mmt_energy_rate_w,
       .hi = 10.0},
      {.key = "mmt_energy_burst_j",
       .unit = "J",
       .help = "energy model updates may add at the master at once",
       .field = &P::mmt_energy_burst_j,
       .hi = 1.0},
  };
  return table;
}

void ModelMediatedController::on_activate(const DeviceReading& /*master*/) {
  status_ = ModelStatus{};
  status_.budget_j = params_.mmt_energy_burst_j;
}

void ModelMediatedController::blend_toward(const mmt::LocalModel& target, const Eigen::Vector3d& x,
                                           double dt_s) {
  mmt::LocalModel& cur = status_.rendered;
  // the device renders alpha beta k: keep it within the stiffness and damping it can render
  const WorkspaceMap& w = params_.workspace;
  const double ab = std::max(1e-9, w.position_scale * w.force_scale);
  mmt::LocalModel tgt = target;
  tgt.stiffness_n_per_m = std::min(tgt.stiffness_n_per_m, spec_.max_stiffness_n_per_m / ab);
  tgt.damping_ns_per_m = std::min(tgt.damping_ns_per_m, spec_.max_damping_ns_per_m / ab);
  mmt::LocalModel next = tgt;
  if (cur.valid && cur.normal.dot(tgt.normal) > std::cos(25.0 * M_PI / 180.0)) {
    // the same surface, moved or re-estimated: a first-order step toward the new model
    const double a = std::min(1.0, dt_s / params_.mmt_blend_s);
    next.normal = (cur.normal + a * (tgt.normal - cur.normal)).normalized();
    next.offset_m = cur.offset_m + a * (tgt.offset_m - cur.offset_m);
    next.stiffness_n_per_m =
        cur.stiffness_n_per_m + a * (tgt.stiffness_n_per_m - cur.stiffness_n_per_m);
    next.damping_ns_per_m =
        cur.damping_ns_per_m + a * (tgt.damping_ns_per_m - cur.damping_ns_per_m);
  }
  // energy the update would add where the master is: within the budget, else the surface
  // moves out so that it adds exactly the budget
  const double before_j = cur.valid ? cur.energy_j(x) : 0.0;
  double added_j = next.energy_j(x) - before_j;
  if (added_j > status_.budget_j) {
    const double allowed_j = before_j + status_.budget_j;
    next.offset_m = next.normal.dot(x) + std::sqrt(2.0 * allowed_j / next.stiffness_n_per_m);
    added_j = status_.budget_j;
    ++status_.limited_updates;
  }
  if (added_j > 0.0) {
    status_.budget_j -= added_j;
    status_.injected_j += added_j;
  }
  cur = next;
}

void ModelMediatedController::compute(const DeviceReading& master, const SlaveSample& slave,
                                      double dt_s, ControlOutput& out) {
  const WorkspaceMap& w = params_.workspace;
  const Eigen::Vector3d x = out.command.position_m;  // the master in the slave frame
  const Eigen::Vector3d v = w.to_slave_velocity(master.linear_velocity_mps);
  status_.budget_j =
      std::min(params_.mmt_energy_burst_j, status_.budget_j + params_.mmt_energy_rate_w * dt_s);
  mmt::LocalModel& cur = status_.rendered;
  if (slave.valid && slave.model.valid && slave.model.stiffness_n_per_m > 0.0) {
    ++status_.models_received;
    blend_toward(slave.model, x, dt_s);
  } else if (cur.valid) {
    // nothing near the slave any more: the model softens away (its energy only falls)
    cur.stiffness_n_per_m *= 1.0 - std::min(1.0, dt_s / params_.mmt_blend_s);
    cur.damping_ns_per_m *= 1.0 - std::min(1.0, dt_s / params_.mmt_blend_s);
    if (cur.stiffness_n_per_m < 1e-3) cur.valid = false;
  }
  const Eigen::Vector3d f_model = cur.force_n(x, v);
  status_.damping_share =
      laws::ramp_toward(status_.damping_share, f_model.squaredNorm() > 0.0 ? 1.0 : 0.0,
                        dt_s / params_.contact_damping_ramp_s);
  out.force_n =
      w.to_master_force(f_model) - status_.damping_share * b_m_ * master.linear_velocity_mps;
}

}  // namespace teleop::master
