#pragma once
// `teleop_play FILE --info`: what a recording holds and how it was read.
#include <string>

namespace teleop::record {

/// Reads every sample of `path` (each MCAP chunk's CRC, each sample's sizes) and describes the
/// file: format, how it was read (summary or recovery, and what was dropped), span, topics and
/// their counts, the whole-file check. @throws as RecordingReader does (a damaged file).
std::string recording_info(const std::string& path);

}  // namespace teleop::record
