#pragma once
// The model-mediated scheme, master side (client/control/bilateral_controller.hpp has the base).
//
// model-mediated (docs/control.md): the slave sends, with each state, a local model of what its
//   tip touches (common/control/contact_model.hpp: a half-space with a stiffness and damping
//   estimated online); the master renders F_m = beta R^T F_model(x_m, v_m) - B_m v_m from its
//   own position at its own rate, and commands the slave x_c = map(x_m) as position-position
//   does. Model updates are blended in (time constant mmt_blend_s); a blend step that would
//   raise the model's stored energy at the master's position by more than an energy budget
//   (refilled at mmt_energy_rate_w up to mmt_energy_burst_j) moves the surface out instead, so
//   late or changing models cannot push the operator with more than that energy.

#include "client/control/bilateral_controller.hpp"
#include "common/control/contact_model.hpp"

namespace teleop::master {

/// Model-mediated teleoperation, master side (see the file comment).
class ModelMediatedController final : public BilateralController {
 public:
  const char* name() const override { return "model-mediated"; }
  SchemeId scheme() const override { return SchemeId::kModelMediated; }
  /// What the shared code asks of it (client/control/scheme_traits.hpp), in its .cpp.
  static SchemeTraits traits(const ControllerParams& params);
  /// Its own parameters (client/control/controller_params.hpp), declared in its .cpp.
  static const std::vector<ControllerParam>& parameters();
  /// The model rendered now (slave frame), and the energy bookkeeping of model updates.
  struct ModelStatus {
    mmt::LocalModel rendered;
    double injected_j = 0.0;            ///< energy model updates added at the master [J]
    double budget_j = 0.0;              ///< what they may add now [J]
    std::uint64_t limited_updates = 0;  ///< blend steps held to the budget
    std::uint64_t models_received = 0;  ///< cycles with a valid model from the slave
    double damping_share = 0.0;         ///< of B_m, ramped to 1 while the model pushes
  };
  const ModelStatus& model_status() const { return status_; }

 protected:
  void on_activate(const DeviceReading& master) override;
  void compute(const DeviceReading& master, const SlaveSample& slave, double dt_s,
               ControlOutput& out) override;

 private:
  /// The rendered model one blend step toward `target` at master position x, within the budget.
  void blend_toward(const mmt::LocalModel& target, const Eigen::Vector3d& x, double dt_s);

  ModelStatus status_;
};

}  // namespace teleop::master
