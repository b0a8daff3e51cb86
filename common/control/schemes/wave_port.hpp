#pragma once
// The port fields of wave variables (wave-variables): what the scheme sends and receives
// beyond the common position/force, the checks on them and their one conversion to and from
// the wire. The wire messages (teleop::MasterCommand, teleop::SlaveState of idl/Teleop.idl)
// are template parameters, so this header needs no DDS. Generic code reaches these functions
// through for_each_port() (common/control/bilateral_types.hpp), which lists every scheme's
// port once.
#include <Eigen/Core>
#include <cmath>
#include <cstdint>

namespace teleop {

namespace passivity {
/// Allowed range of the wave impedance b [N s/m] on the wire (the master clamps tighter).
inline constexpr double kMinWaveImpedance = 0.01;
inline constexpr double kMaxWaveImpedance = 1.0e4;
/// A reconstructed wave is limited to the wave of a port moving at this speed [m/s] ...
inline constexpr double kWaveLimitSpeedMps = 2.0;
/// ... while pushing with this force [N] (only reached when a receiver catches up a gap).
inline constexpr double kWaveLimitForceN = 200.0;
}  // namespace passivity

/// The wave-variables fields of a command and of a sample, in the slave frame.
struct WavePort {
  /// The wire's scheme byte of wave variables (checked against SchemeId in
  /// common/control/bilateral_types.hpp).
  static constexpr std::uint8_t kScheme = 2;
  /// Master -> slave.
  struct Command {
    Eigen::Vector3d u = Eigen::Vector3d::Zero();  ///< forward wave this cycle [sqrt(W)]
    double impedance_ns_per_m = 0.0;              ///< b [N s/m]
    bool matched = true;  ///< the slave terminates the channel with a damper b
    Eigen::Vector3d u_integral = Eigen::Vector3d::Zero();  ///< sum dt u [sqrt(W) s]
    Eigen::Vector3d u_energy_j = Eigen::Vector3d::Zero();  ///< sum dt u^2/2 per axis [J]
  };
  /// Slave -> master.
  struct State {
    Eigen::Vector3d v = Eigen::Vector3d::Zero();           ///< backward wave this step [sqrt(W)]
    Eigen::Vector3d v_integral = Eigen::Vector3d::Zero();  ///< sum dt v [sqrt(W) s]
    Eigen::Vector3d v_energy_j = Eigen::Vector3d::Zero();  ///< sum dt v^2/2 per axis [J]
  };
};

/// True if every field is finite.
inline bool all_finite(const WavePort::Command& c) {
  return c.u.allFinite() && c.u_integral.allFinite() && c.u_energy_j.allFinite() &&
         std::isfinite(c.impedance_ns_per_m);
}
inline bool all_finite(const WavePort::State& s) {
  return s.v.allFinite() && s.v_integral.allFinite() && s.v_energy_j.allFinite();
}
/// True unless `scheme` is wave variables and b is outside [kMinWaveImpedance,
/// kMaxWaveImpedance].
inline bool in_range(const WavePort::Command& c, std::uint8_t scheme) {
  return scheme != WavePort::kScheme || (c.impedance_ns_per_m >= passivity::kMinWaveImpedance &&
                                         c.impedance_ns_per_m <= passivity::kMaxWaveImpedance);
}
/// True if an energy is below zero.
inline bool any_negative(const WavePort::Command& c) { return (c.u_energy_j.array() < 0.0).any(); }
/// True if a cumulative energy of `now` is below that of `last` by more than `tol_j` [J].
inline bool decreased(const WavePort::Command& now, const WavePort::Command& last, double tol_j) {
  return (now.u_energy_j.array() < last.u_energy_j.array() - tol_j).any();
}

namespace wave_wire {
template <class Array>
void put3(Array& out, const Eigen::Vector3d& v) {
  out[0] = v.x();
  out[1] = v.y();
  out[2] = v.z();
}
template <class Array>
Eigen::Vector3d get3(const Array& a) {
  return Eigen::Vector3d(a[0], a[1], a[2]);
}
}  // namespace wave_wire

/// Command fields -> teleop::MasterCommand.
template <class Message>
void to_wire(const WavePort::Command& c, Message& m) {
  wave_wire::put3(m.wave_u(), c.u);
  m.wave_impedance_ns_per_m(c.impedance_ns_per_m);
  m.wave_matched(c.matched);
  wave_wire::put3(m.wave_u_integral(), c.u_integral);
  wave_wire::put3(m.wave_u_energy_j(), c.u_energy_j);
}
/// teleop::MasterCommand -> command fields.
template <class Message>
void from_wire(const Message& m, WavePort::Command& c) {
  c.u = wave_wire::get3(m.wave_u());
  c.impedance_ns_per_m = m.wave_impedance_ns_per_m();
  c.matched = m.wave_matched();
  c.u_integral = wave_wire::get3(m.wave_u_integral());
  c.u_energy_j = wave_wire::get3(m.wave_u_energy_j());
}
/// Sample fields -> teleop::SlaveState.
template <class Message>
void to_wire(const WavePort::State& s, Message& m) {
  wave_wire::put3(m.wave_v(), s.v);
  wave_wire::put3(m.wave_v_integral(), s.v_integral);
  wave_wire::put3(m.wave_v_energy_j(), s.v_energy_j);
}
/// teleop::SlaveState -> sample fields.
template <class Message>
void from_wire(const Message& m, WavePort::State& s) {
  s.v = wave_wire::get3(m.wave_v());
  s.v_integral = wave_wire::get3(m.wave_v_integral());
  s.v_energy_j = wave_wire::get3(m.wave_v_energy_j());
}

}  // namespace teleop
