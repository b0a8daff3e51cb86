#pragma once
// The tdpa scheme, master side (client/control/bilateral_controller.hpp has the base).
//
// tdpa (Hannaford & Ryu 2002; Ryu, Artigas & Preusche 2010): position-position or
//   force-position (tdpa_base) with the master's passivity observer and controller
//   (common/control/time_domain_passivity.hpp): the force is modified by the adaptive damping
//   that keeps the master port's output energy within the slave port's input energy
//   received; the command carries the master port's input energy for the slave's PC.
#include "client/control/bilateral_controller.hpp"
#include "common/control/time_domain_passivity.hpp"

namespace teleop::master {

/// Time-domain passivity on top of position-position or force-position (see the file comment).
class TimeDomainPassivityController final : public BilateralController {
 public:
  const char* name() const override { return "tdpa"; }
  SchemeId scheme() const override { return SchemeId::kTimeDomainPassivity; }
  /// What the shared code asks of it (client/control/scheme_traits.hpp), in its .cpp.
  static SchemeTraits traits(const ControllerParams& params);
  /// Its variants: "tdpa" (on position-position) and "tdpa-fp" (on force-position).
  static const std::vector<SchemeVariant>& variants();
  /// Its own parameters (client/control/controller_params.hpp), declared in its .cpp.
  static const std::vector<ControllerParam>& parameters();
  double environment_force_gain() const override {
    return force_position_ ? params_.force_gain : 1.0;
  }
  PassivityStatus passivity_status() const override;
  /// The master's observer/controller (master-frame energies).
  const passivity::ImpedancePassivityController& pc() const { return pc_; }
  /// Slave port energies received, converted to the master frame [J].
  double remote_in_j() const { return remote_in_j_; }
  double remote_out_j() const { return remote_out_j_; }

 protected:
  void on_configure() override;
  void on_activate(const DeviceReading& master) override;
  void compute(const DeviceReading& master, const SlaveSample& slave, double dt_s,
               ControlOutput& out) override;
  void finish(const DeviceReading& master, const SlaveSample& slave, double dt_s,
              ControlOutput& out) override;

 private:
  bool force_position_ = false;
  passivity::ImpedancePassivityController pc_;
  Eigen::Vector3d wanted_n_ = Eigen::Vector3d::Zero();
  double remote_in_j_ = 0.0;
  double remote_out_j_ = 0.0;
};

}  // namespace teleop::master
