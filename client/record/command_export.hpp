#pragma once
// The master's commands of a recording as a command stream (common/util/command_stream.hpp),
// the input of the server's off-line re-simulation (`teleop_experiment resim`).
#include <cstddef>
#include <string>

namespace teleop::record {

/// Writes every teleop/master_command sample of `recording` into `out`, in receive order.
/// Returns how many. @throws RecordingError (not a recording, or no commands in it),
/// std::runtime_error (cannot write `out`).
std::size_t export_command_stream(const std::string& recording, const std::string& out);

}  // namespace teleop::record
