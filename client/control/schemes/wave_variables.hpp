#pragma once
// The wave-variables scheme, master side (client/control/bilateral_controller.hpp has the base).
//
// wave-variables (Niemeyer & Slotine; Anderson & Spong 1989): the master port of a wave
//   channel of impedance b (common/control/wave_variables.hpp). The device renders
//   -beta R^T F_m - B_m v_m with F_m = b xdot_m - sqrt(2b) v_m in the slave frame; the
//   command carries the forward wave u, its integral and its energy; the slave decodes them
//   with its contact force (common/control/slave_port.hpp) and returns the backward wave.
#include "client/control/bilateral_controller.hpp"
#include "common/control/wave_variables.hpp"

namespace teleop::master {

/// Wave variables, master side (see the file comment).
class WaveVariablesController final : public BilateralController {
 public:
  const char* name() const override { return "wave-variables"; }
  SchemeId scheme() const override { return SchemeId::kWaveVariables; }
  /// What the shared code asks of it (client/control/scheme_traits.hpp), in its .cpp.
  static SchemeTraits traits(const ControllerParams& params);
  /// Its own parameters (client/control/controller_params.hpp), declared in its .cpp.
  static const std::vector<ControllerParam>& parameters();
  /// Effective wave impedance b after derivation and clamping [N s/m].
  double wave_impedance_ns_per_m() const override { return b_; }
  /// The master port (waves, integrals, energies).
  const passivity::WaveMasterPort& port() const { return port_; }
  PassivityStatus passivity_status() const override;

 protected:
  void on_configure() override;
  void on_activate(const DeviceReading& master) override;
  void compute(const DeviceReading& master, const SlaveSample& slave, double dt_s,
               ControlOutput& out) override;

 private:
  double b_ = 0.0;
  passivity::WaveMasterPort port_;
  Eigen::Vector3d v_energy_rx_ = Eigen::Vector3d::Zero();
};

}  // namespace teleop::master
