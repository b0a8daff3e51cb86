#pragma once
// The slave side of the passivity-based schemes, in one place for every slave: the server's
// ServerCycle, networked or in-process (server::WorldSlave under LoopbackSession, `teleop_bench
// delay`). No DDS here: the callers convert their command and
// state types to the plain structs below.
//
//   wave variables (SCHEME_WAVE_VARIABLES): WaveSlaveLaw (common/control/schemes/wave_slave.hpp).
//   time-domain passivity (SCHEME_TIME_DOMAIN_PASSIVITY): TdpaSlaveLaw
//     (common/control/schemes/tdpa_slave.hpp).
//   other schemes: the command passes unchanged.
//
// Per step:  target = port.before_step(cmd, state, gains, dt);  <step the slave to target>;
//            port.after_step(tracking_force, dt);  report() -> the state message.
// A new session id (or a new scheme) restarts the port's state. Allocation-free.
#include <Eigen/Core>
#include <cstdint>

#include "common/control/bilateral_types.hpp"
#include "common/control/schemes/tdpa_slave.hpp"
#include "common/control/schemes/wave_slave.hpp"

namespace teleop::passivity {

/// The wire's scheme bytes of the schemes with a slave side (SchemeId, common/control/
/// bilateral_types.hpp, checked against idl/Teleop.idl in client/control/schemes/registry.cpp).
inline constexpr std::uint8_t kSchemeWaveVariables =
    static_cast<std::uint8_t>(SchemeId::kWaveVariables);
inline constexpr std::uint8_t kSchemeTimeDomainPassivity =
    static_cast<std::uint8_t>(SchemeId::kTimeDomainPassivity);

/// The passivity fields of a command as the slave received it (slave frame, SI).
struct SlavePortCommand {
  std::uint8_t scheme = 0;           ///< SCHEME_* constant
  std::uint32_t session = 0;         ///< master's session id (0: none)
  bool enabled = false;              ///< false: the slave holds
  Vec3 position_m = Vec3::Zero();    ///< master's mapped position [m]
  Vec3 velocity_mps = Vec3::Zero();  ///< master's mapped velocity [m/s]
  WavePort::Command wave;            ///< wave variables' port fields
  TdpaPort::Command tdpa;            ///< time-domain passivity's port fields
};

/// Why a command's passivity fields are unusable (the server counts these as rejections).
enum class PortCommandCheck : std::uint8_t {
  kOk = 0,
  kNonFinite,        ///< NaN or Inf in a wave or energy field
  kBadImpedance,     ///< wave scheme with b outside [kMinWaveImpedance, kMaxWaveImpedance]
  kNegativeEnergy,   ///< an energy below zero
  kEnergyDecreased,  ///< a cumulative energy went down within a session (stale or corrupt)
};
const char* to_string(PortCommandCheck c);

/// Checks the fields of `c` alone (finite, ranges); the port also checks monotonicity.
PortCommandCheck check_port_command(const SlavePortCommand& c);

/// True if a cumulative energy of `now` is below that of `last` by more than `tol_j` [J]
/// (within a session energies never decrease: an older command is stale or corrupt).
bool energy_decreased(const SlavePortCommand& now, const SlavePortCommand& last, double tol_j);

/// The slave's state before a step (slave frame).
struct SlavePortState {
  Vec3 position_m = Vec3::Zero();       ///< tool position [m]
  Vec3 velocity_mps = Vec3::Zero();     ///< tool velocity [m/s]
  Vec3 contact_force_n = Vec3::Zero();  ///< environment force on the tool, last step [N]
};

/// The slave's tracking law f = kp (x_cmd - x) + kd (v_cmd - v) (the PD the command drives).
struct TrackingGains {
  double kp_n_per_m = 400.0;  ///< [N/m]
  double kd_ns_per_m = 12.0;  ///< [N s/m]
};

/// What the slave's tracking controller gets this step.
struct SlavePortTarget {
  Vec3 position_m = Vec3::Zero();    ///< [m]
  Vec3 velocity_mps = Vec3::Zero();  ///< feed-forward [m/s]
  bool hold = false;                 ///< hold the current pose instead
};

/// What goes back to the master (the passivity fields of the state message).
struct SlavePortReport {
  std::uint32_t session = 0;  ///< session these fields belong to (0: none)
  WavePort::State wave;       ///< wave variables' port fields
  TdpaPort::State tdpa;       ///< time-domain passivity's port fields
  double dissipated_j = 0.0;  ///< slave-side PC / matching damper [J]
};

/// Parameters of the slave port.
struct SlavePortParams {
  double drift_time_constant_s = 0.5;  ///< TDPA: decay time of the PC's command offset [s]
};

/// The slave side of wave variables and TDPA. See the file comment.
class SlavePassivityPort {
 public:
  explicit SlavePassivityPort(const SlavePortParams& params = {}) : params_(params) {}

  /// Forgets the session.
  void reset();
  /// True if `scheme` is one this port transforms.
  static bool handles(std::uint8_t scheme) {
    return scheme == kSchemeWaveVariables || scheme == kSchemeTimeDomainPassivity;
  }
  /// Before the slave steps: the target for its tracking controller. A command the port
  /// cannot use (check_port_command() fails, or an energy went down) holds the slave and
  /// counts a rejection; the caller that validated at the edge never sees one.
  SlavePortTarget before_step(const SlavePortCommand& cmd, const SlavePortState& state,
                              const TrackingGains& gains, double dt_s);
  /// After the step: the tracking force the controller applied to the tool [N].
  void after_step(const Vec3& tracking_force_n, double dt_s);

  const SlavePortReport& report() const { return report_; }
  /// Scheme of the running session (0xff: none).
  std::uint8_t scheme() const { return scheme_; }
  /// Commands refused by before_step() so far.
  std::uint64_t rejected() const { return rejected_; }
  const WaveSlavePort& wave() const { return wave_.port(); }
  const AdmittancePassivityController& tdpa() const { return tdpa_.controller(); }

 private:
  void start(const SlavePortCommand& cmd);

  SlavePortParams params_;
  WaveSlaveLaw wave_;
  TdpaSlaveLaw tdpa_;
  SlavePortReport report_;
  std::uint8_t scheme_ = 0xff;
  std::uint32_t session_ = 0;
  bool active_ = false;
  bool stepped_tdpa_ = false;
  SlavePortCommand last_;  ///< the newest accepted command's cumulative fields
  std::uint64_t rejected_ = 0;
};

/// The passivity fields of a command as the slave port reads them (the one conversion, used by
/// the server and the in-process slaves alike).
SlavePortCommand port_command(const SlaveCommand& c);
/// Copies the slave port's report into a sample's passivity fields.
void apply_port_report(const SlavePortReport& r, SlaveSample& s);

}  // namespace teleop::passivity
