#pragma once
// Validation of MasterCommand samples at the network edge: a command with NaN/Inf, a bad
// quaternion, a position outside the workspace, or an old sequence number is rejected and
// counted; it never reaches the physics.
#include <Eigen/Core>
#include <cstdint>

#include "server/world/world.hpp"
#include "teleop/idl/Teleop.h"

namespace teleop::server {

enum class CommandVerdict {
  kAccepted,
  kNonFinite,         ///< a NaN or Inf in any numeric field
  kBadOrientation,    ///< quaternion norm outside [0.5, 2]
  kOutsideWorkspace,  ///< position outside the scene's command workspace
  kBadGain,           ///< negative or absurd position gain override
  kStale,             ///< sequence number not newer than the last accepted one
};

const char* to_string(CommandVerdict v);

/// Checks one command. `last_seq`/`have_last`: newest accepted seq from the same writer.
CommandVerdict validate_command(const MasterCommand& cmd, const Eigen::Vector3d& workspace_min_m,
                                const Eigen::Vector3d& workspace_max_m, std::uint64_t last_seq,
                                bool have_last);

/// Converts an accepted command to the world's input (normalises the quaternion).
sim::WorldCommand to_world_command(const MasterCommand& cmd);

}  // namespace teleop::server
