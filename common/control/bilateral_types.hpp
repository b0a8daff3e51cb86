#pragma once
// Types exchanged by the bilateral controller: what the master sends to the slave
// (SlaveCommand, mirrors teleop::MasterCommand), what comes back (SlaveSample, mirrors
// teleop::SlaveState), and the map between the master's and the slave's workspaces.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

#include "common/control/contact_model.hpp"
#include "common/control/schemes/tdpa_port.hpp"
#include "common/control/schemes/wave_port.hpp"

namespace teleop {

/// Scheme ids, equal to the SCHEME_* constants of idl/Teleop.idl.
enum class SchemeId : std::uint8_t {
  kPositionPosition = 0,
  kForcePosition = 1,
  kWaveVariables = 2,
  kTimeDomainPassivity = 3,
  kModelMediated = 4,
};

static_assert(WavePort::kScheme == static_cast<std::uint8_t>(SchemeId::kWaveVariables));

/// Master -> slave, slave frame. Mirrors teleop::MasterCommand.
struct SlaveCommand {
  std::uint64_t seq = 0;                                            ///< command counter
  double send_time_s = 0.0;                                         ///< master clock when sent [s]
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();             ///< commanded tool position [m]
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< commanded orientation
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();           ///< commanded velocity [m/s]
  Eigen::Vector3d angular_velocity_radps = Eigen::Vector3d::Zero();  ///< [rad/s]
  Eigen::Vector3d master_force_n = Eigen::Vector3d::Zero();  ///< force rendered at the master,
                                                             ///< slave frame [N]
  double position_gain_n_per_m = 0.0;  ///< K_ps requested from the slave (0 = its default)
  SchemeId scheme = SchemeId::kPositionPosition;
  bool enabled = true;   ///< false: the slave holds its pose
  bool release = false;  ///< the master gives the slave up (its last commands; ownership)
  // passivity schemes (see common/control/slave_port.hpp)
  std::uint32_t passivity_session = 0;  ///< session id of a passivity scheme's run (0: none)
  WavePort::Command wave;               ///< wave variables' port fields
  TdpaPort::Command tdpa;               ///< time-domain passivity's port fields
};

/// Slave -> master, slave frame. Mirrors teleop::SlaveState (the parts the master uses).
struct SlaveSample {
  std::uint64_t seq = 0;                                 ///< slave step counter
  std::uint64_t command_seq = 0;                         ///< newest command applied (echo)
  double command_send_time_s = 0.0;                      ///< that command's send time, echoed [s]
  double sim_time_s = 0.0;                               ///< slave clock [s]
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  ///< tool tip [m]
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();     ///< [m/s]
  Eigen::Vector3d contact_force_n = Eigen::Vector3d::Zero();  ///< environment force on tip [N]
  double penetration_m = 0.0;                                 ///< deepest penetration [m]
  double deformation_m = 0.0;  ///< indentation of a deformable body since contact began [m]
  bool in_contact = false;     ///< tip touches something
  bool valid = false;          ///< false: no sample received yet
  /// Which life of the slave this sample comes from: the transport counts the slave's
  /// restarts (a new server instance starts from home); a master re-homes when it changes.
  std::uint32_t slave_epoch = 0;
  /// What the tip touches or is about to (model-mediated scheme, common/control/contact_model).
  mmt::LocalModel model;
  // passivity schemes (see common/control/slave_port.hpp)
  std::uint32_t passivity_session = 0;  ///< session the fields below belong to (0: none)
  WavePort::State wave;                 ///< wave variables' port fields
  TdpaPort::State tdpa;                 ///< time-domain passivity's port fields
  double passivity_dissipated_j = 0.0;  ///< removed at the slave side [J]
};

/// The schemes' port fields, registered once: calls `f` with the port struct of each scheme
/// that has one, taken from every message in `m` (a command-like type: SlaveCommand,
/// passivity::SlavePortCommand, ...; or a sample-like type: SlaveSample,
/// passivity::SlavePortReport, ...). The IDL conversion, the validation and the slave port's
/// report reach each scheme's functions (next to its port struct) only through this.
template <class F, class... Messages>
void for_each_port(F&& f, Messages&... m) {
  f(m.wave...);
  f(m.tdpa...);
}

/// True if every scheme's port fields of `m` are finite.
template <class Message>
bool ports_finite(const Message& m) {
  bool ok = true;
  for_each_port([&ok](const auto& p) { ok = ok && all_finite(p); }, m);
  return ok;
}

/// Master (device) frame <-> slave (world) frame. x_s = offset + s R x_m; f_m = k_f R^T f_s.
struct WorkspaceMap {
  Eigen::Vector3d offset_m = Eigen::Vector3d::Zero();  ///< slave point of the master origin [m]
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  ///< master -> slave rotation
  double position_scale = 1.0;  ///< alpha: slave metres per master metre [-]
  double force_scale = 1.0;     ///< beta: master newtons per slave newton [-]

  /// Master position [m] -> slave position [m].
  Eigen::Vector3d to_slave_position(const Eigen::Vector3d& x_m) const {
    return offset_m + position_scale * (rotation * x_m);
  }
  /// Master velocity [m/s] -> slave velocity [m/s].
  Eigen::Vector3d to_slave_velocity(const Eigen::Vector3d& v) const {
    return position_scale * (rotation * v);
  }
  /// Slave position [m] -> master position [m].
  Eigen::Vector3d to_master_position(const Eigen::Vector3d& x_s) const {
    return rotation.conjugate() * ((x_s - offset_m) / position_scale);
  }
  /// Slave force [N] -> master force [N] (scaled by force_scale).
  Eigen::Vector3d to_master_force(const Eigen::Vector3d& f_s) const {
    return force_scale * (rotation.conjugate() * f_s);
  }
  /// Master force [N] -> slave frame [N] (inverse scaling).
  Eigen::Vector3d to_slave_force(const Eigen::Vector3d& f_m) const {
    return (rotation * f_m) / force_scale;
  }
};

}  // namespace teleop
