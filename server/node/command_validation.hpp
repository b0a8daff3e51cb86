#pragma once
// Validation of MasterCommand samples at the network edge: a command with NaN/Inf, a bad
// quaternion, a position outside the workspace, an old sequence number, or unusable port fields
// of a passivity scheme (a field out of its range, a negative energy, a cumulative energy that
// went down within a session) is rejected and counted; it never reaches the physics.
#include <Eigen/Core>
#include <cstdint>

#include "common/control/slave_port.hpp"
#include "teleop/idl/Teleop.h"

namespace teleop::server {

enum class CommandVerdict {
  kAccepted,
  kNonFinite,         ///< a NaN or Inf in any numeric field, or an absurd velocity / force
  kBadOrientation,    ///< quaternion norm outside [0.5, 2]
  kOutsideWorkspace,  ///< position outside the scene's command workspace
  kBadGain,           ///< negative or absurd position gain override
  kStale,             ///< sequence number not newer than the last accepted one
  kBadPassivity,      ///< a scheme's port fields out of range (b, negative or decreasing energy)
};

const char* to_string(CommandVerdict v);

/// Magnitudes beyond which a finite command field is malformed (rejected as kNonFinite): far
/// above anything a device or the slave can do, low enough that one step of the slave law on
/// them stays finite (fuzz_command found velocities of 1e219 m/s that made the tool's state NaN).
constexpr double kMaxCommandSpeedMps = 100.0;            ///< |linear_velocity_mps|
constexpr double kMaxCommandAngularSpeedRadps = 1000.0;  ///< |angular_velocity_radps|
constexpr double kMaxCommandForceN = 1e5;                ///< |master_force_n|

/// Checks one command. `last_seq`/`have_last`: newest accepted seq from the same writer.
CommandVerdict validate_command(const MasterCommand& cmd, const Eigen::Vector3d& workspace_min_m,
                                const Eigen::Vector3d& workspace_max_m, std::uint64_t last_seq,
                                bool have_last);

/// Newest accepted passivity fields of one writer, to catch energies that go backwards.
struct PassivityHistory {
  bool have = false;
  std::uint32_t session = 0;
  passivity::SlavePortCommand last;  ///< the newest accepted fields (cumulative energies)
};

/// Checks the passivity fields of `cmd` (after validate_command() accepted the rest) against
/// the writer's history; on kAccepted updates `history`.
CommandVerdict validate_passivity(const MasterCommand& cmd, PassivityHistory& history);

}  // namespace teleop::server
