#pragma once
// Converts a recording from one format to the other (recording.hpp), sample for sample: the
// same topics, types, QoS classes, times, writers and payloads, in receive order. An old SQLite
// recording becomes an MCAP file that Foxglove or Lichtblick open.
#include <cstdint>
#include <string>

#include "common/record/recording.hpp"

namespace teleop::record {

/// Writes every sample of `in` into a new recording `out` of `format`; returns how many.
/// @throws as RecordingReader and RecordingWriter do.
std::uint64_t convert_recording(const std::string& in, const std::string& out,
                                RecordingFormat format);

}  // namespace teleop::record
