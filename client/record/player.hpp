#pragma once
// The player behind teleop_play: publishes a recording back on a DDS domain, each topic with
// the QoS class it was recorded with, each sample's serialized payload as it was received,
// paced by the recorded receive times (scaled by `speed`), starting `seek_s` into the
// recording. Latched topics (scene, mesh topology, events) recorded before the seek point are
// published first, so an observer sees the world as it was at that moment; their writers are
// transient local, so observers that join later still get them.
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "common/dds/participant.hpp"

namespace teleop::record {

struct PlayerOptions {
  std::string file;
  double speed = 1.0;                ///< 1 = as recorded, 2 = twice as fast
  double seek_s = 0.0;               ///< start this far into the recording [s]
  double wait_s = 0.5;               ///< pause after creating the writers, for discovery [s]
  double linger_s = 1.0;             ///< keep the writers after the last sample [s]
  double max_gap_s = 10.0;           ///< a longer pause between samples is cut to this [s]
  std::vector<std::string> exclude;  ///< topic names not to publish
  bool quiet = false;
  std::FILE* progress = nullptr;  ///< where the progress line goes (recording time played)
};

struct PlayerResult {
  std::uint64_t written = 0;         ///< samples written
  std::uint64_t failures = 0;        ///< write() refused by the middleware
  std::uint64_t skipped_topics = 0;  ///< topics of unknown type, not published
  std::uint64_t gaps_skipped = 0;    ///< pauses longer than max_gap_s, cut short
  double recording_s = 0.0;          ///< length of the recording [s]
};

/// Plays the recording until its end or a stop request (SIGINT/SIGTERM).
/// @throws RecordingError, DdsError, config::ConfigError (seek beyond the end).
PlayerResult play(dds::Participant& participant, const PlayerOptions& options);

}  // namespace teleop::record
