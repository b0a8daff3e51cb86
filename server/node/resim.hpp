#pragma once
// Off-line, deterministic re-simulation of a session from its command stream: the
// server's own cycle (validation at the edge, watchdog, passivity port, world step) driven by
// the recorded commands on a simulated clock instead of the network and the wall clock.
//
// The physics steps at t_k = t_0 + k dt, t_0 the first command's receive time. Before step k,
// every command received at or before t_k goes through the node's own edge (command_gate.hpp:
// field checks, ownership, the owner's sequence and passivity fields; outcomes counted by
// reason) in receive order, and the newest accepted one goes to the cycle, as the node's mailbox
// does. Nothing reads a clock: the same stream and scene give the same states, forces and
// events, bit for bit, on every run; `hash` is a 64-bit FNV-1a over them to compare runs.
#include <cstdint>
#include <functional>
#include <vector>

#include "common/sim/events.hpp"
#include "common/util/command_stream.hpp"
#include "server/world/world.hpp"

namespace teleop::server {

struct ResimOptions {
  double rate_hz = 1000.0;       ///< physics rate [Hz]
  double tail_s = 0.5;           ///< steps after the last command (the watchdog's hold shows) [s]
  double owner_timeout_s = 0.5;  ///< the ownership watchdog, as the node's --owner-timeout [s]
};

/// One physics step's result, as the server would publish it.
struct ResimStep {
  std::uint64_t step = 0;
  double sim_time_s = 0.0;
  std::uint64_t command_seq = 0;  ///< seq of the command the slave tracked
  bool holding = false;           ///< watchdog / disabled / port hold
  const sim::WorldOutput* out = nullptr;
};

struct ResimResult {
  std::uint64_t steps = 0;
  std::uint64_t commands = 0;  ///< in the stream
  std::uint64_t accepted = 0;
  std::uint64_t rejected_nan = 0, rejected_workspace = 0, rejected_stale = 0,
                rejected_passivity = 0, undecodable = 0;
  std::uint64_t refused_owner = 0;  ///< from a master that did not own the slave
  std::uint64_t masters = 0;        ///< owners the slave had
  std::uint64_t events = 0;
  std::uint64_t watchdog_trips = 0;
  std::uint64_t hash = 0;  ///< FNV-1a 64 over every step's state and every event
};

/// Runs the stream through a fresh world of `model`. `on_step` / `on_event` (optional) see
/// every step and event, e.g. to write them to CSV.
ResimResult resimulate(const sim::WorldModel& model, const std::vector<StreamedCommand>& stream,
                       const ResimOptions& options,
                       const std::function<void(const ResimStep&)>& on_step = {},
                       const std::function<void(const sim::SimEvent&)>& on_event = {});

}  // namespace teleop::server
