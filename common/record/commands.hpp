#pragma once
// The master's commands of a recording (either format) as a command stream
// (common/util/command_stream.hpp): the input of the server's off-line re-simulation
// (`teleop_experiment resim --recording`, or `teleop_play --export-commands` then
// `teleop_experiment resim --commands`).
#include <cstddef>
#include <string>
#include <vector>

#include "common/util/command_stream.hpp"

namespace teleop::record {

/// Every teleop/master_command sample of `recording` received from `from_s` to `to_s` seconds
/// after the recording's first sample (to_s <= 0: to the end), in receive order. An MCAP file
/// is read only from the chunks that overlap that window (its chunk index).
/// @throws RecordingError (not a recording, no commands in it or in the window),
/// config::ConfigError (a damaged file, from_s beyond the end).
std::vector<StreamedCommand> recorded_commands(const std::string& recording, double from_s = 0.0,
                                               double to_s = 0.0);

/// Writes every teleop/master_command sample of `recording` into `out`, in receive order.
/// Returns how many. @throws as recorded_commands(), std::runtime_error (cannot write `out`).
std::size_t export_command_stream(const std::string& recording, const std::string& out);

}  // namespace teleop::record
