#pragma once
// The port fields of time-domain passivity (tdpa): what the scheme sends and receives beyond
// the common position/force, the checks on them and their one conversion to and from the
// wire. The wire messages (teleop::MasterCommand, teleop::SlaveState of idl/Teleop.idl) are
// template parameters, so this header needs no DDS. Generic code reaches these functions
// through for_each_port() (common/control/bilateral_types.hpp), which lists every scheme's
// port once.
#include <cmath>
#include <cstdint>

namespace teleop {

/// The tdpa fields of a command and of a sample, in the slave frame.
struct TdpaPort {
  /// Master -> slave.
  struct Command {
    double energy_in_j = 0.0;  ///< energy into the network at the master port [J]
  };
  /// Slave -> master.
  struct State {
    double energy_in_j = 0.0;   ///< energy into the network at the slave port [J]
    double energy_out_j = 0.0;  ///< energy out of the network into the slave [J]
  };
};

/// True if every field is finite.
inline bool all_finite(const TdpaPort::Command& c) { return std::isfinite(c.energy_in_j); }
inline bool all_finite(const TdpaPort::State& s) {
  return std::isfinite(s.energy_in_j) && std::isfinite(s.energy_out_j);
}
/// True: tdpa's fields have no range beyond their sign.
inline bool in_range(const TdpaPort::Command& /*c*/, std::uint8_t /*scheme*/) { return true; }
/// True if an energy is below zero.
inline bool any_negative(const TdpaPort::Command& c) { return c.energy_in_j < 0.0; }
/// True if a cumulative energy of `now` is below that of `last` by more than `tol_j` [J].
inline bool decreased(const TdpaPort::Command& now, const TdpaPort::Command& last, double tol_j) {
  return now.energy_in_j < last.energy_in_j - tol_j;
}

/// Command fields -> teleop::MasterCommand.
template <class Message>
void to_wire(const TdpaPort::Command& c, Message& m) {
  m.tdpa_energy_in_j(c.energy_in_j);
}
/// teleop::MasterCommand -> command fields.
template <class Message>
void from_wire(const Message& m, TdpaPort::Command& c) {
  c.energy_in_j = m.tdpa_energy_in_j();
}
/// Sample fields -> teleop::SlaveState.
template <class Message>
void to_wire(const TdpaPort::State& s, Message& m) {
  m.tdpa_energy_in_j(s.energy_in_j);
  m.tdpa_energy_out_j(s.energy_out_j);
}
/// teleop::SlaveState -> sample fields.
template <class Message>
void from_wire(const Message& m, TdpaPort::State& s) {
  s.energy_in_j = m.tdpa_energy_in_j();
  s.energy_out_j = m.tdpa_energy_out_j();
}

}  // namespace teleop
