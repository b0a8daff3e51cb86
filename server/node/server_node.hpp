#pragma once
// The server's DDS node: owns the world, steps it at a fixed rate, applies the newest valid
// MasterCommand, publishes SlaveState every step, the scene once, mesh frames at the visual
// rate (from its own thread), events on change and ServerStats periodically.
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "common/dds/participant.hpp"
#include "common/util/realtime.hpp"
#include "server/world/world_model.hpp"

namespace teleop::server {

struct ServerOptions {
  dds::ParticipantOptions dds;
  double rate_hz = 1000.0;          ///< physics rate [Hz]
  double command_timeout_s = 0.05;  ///< watchdog [s]
  double owner_timeout_s = 0.5;     ///< ownership watchdog: owner silent this long loses it [s]
  double duration_s = 0.0;          ///< stop after this long; 0 = until SIGINT/SIGTERM [s]
  double stats_period_s = 1.0;      ///< ServerStats period [s]
  int max_observers = 32;           ///< above this many observers, a warning event (and again
                                    ///< after the count fell back and rose past it once more)
  std::string summary_json;         ///< write a JSON summary here at exit (optional)
  RealtimeOptions realtime;         ///< scheduling of the physics loop (common/util/realtime)
  bool quiet = false;
};

/// Counters of commands seen by the reader thread (atomics: written there, read by the loop).
struct CommandCounters {
  std::atomic<std::uint64_t> received{0};
  std::atomic<std::uint64_t> accepted{0};
  std::atomic<std::uint64_t> rejected_nan{0};
  std::atomic<std::uint64_t> rejected_workspace{0};
  std::atomic<std::uint64_t> rejected_stale{0};
  std::atomic<std::uint64_t> rejected_passivity{0};  ///< a scheme's port fields unusable
  std::atomic<std::uint64_t> refused_owner{0};       ///< from a master not owning the slave
};

class ServerNode {
 public:
  /// `model` must outlive the node.
  ServerNode(const ServerOptions& options, const sim::WorldModel& model);
  ~ServerNode();
  /// Runs until stop_requested() or the duration elapses. Returns the process exit status.
  int run();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace teleop::server
