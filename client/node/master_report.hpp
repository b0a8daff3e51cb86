#pragma once
// The master's report of a session (MasterNode): the figures it gathered after the loop
// (SessionReport), the printout on stdout, the JSON summary (--summary-json) and the per-cycle
// CSV log (--log-csv). Everything here reads the session; nothing here changes it.
#include <array>
#include <cstdint>
#include <string>

#include "client/cycle/master_cycle.hpp"
#include "client/metrics/hertz_reference.hpp"
#include "client/metrics/link_verdict.hpp"
#include "client/metrics/session_metrics.hpp"
#include "client/net/delay_channel.hpp"
#include "client/node/master_node.hpp"
#include "client/node/server_binding.hpp"
#include "common/util/csv.hpp"
#include "common/util/json.hpp"
#include "common/util/stats.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::master {

/// What the session measured, gathered once after the loop for the JSON and the printout.
struct SessionReport {
  double elapsed_s = 0.0;
  double session_s = 0.0;
  double wait_s = 0.0;
  std::uint64_t issued = 0;     // commands the cycle issued (into the injected forward channel)
  std::uint64_t in_flight = 0;  // of them, still held in the injected delay when it stopped
  std::uint64_t dropped = 0;    // of them, dropped by the injected channel (loss, burst, overflow)
  std::uint64_t sent = 0;       // written to DDS
  std::uint64_t received = 0;   // received by the server (across its restarts)
  std::uint64_t echoed = 0;
  std::uint64_t states_received = 0;
  std::uint64_t overruns = 0;
  std::uint64_t link_losses = 0;
  std::uint64_t stalls = 0;      // cycles that began a stall's length or more after the last
  double longest_stall_s = 0.0;  // the longest such gap
  Summary rtt_ms;
  Summary loop_delay_ms;
  Summary jitter_us;
  ChannelReport forward;
  ChannelReport backward;
  // the server's side of the session (ServerStats and fault events, across restarts)
  std::uint64_t server_faults = 0;
  std::uint64_t server_watchdog_trips = 0;
  std::uint64_t server_overruns = 0;
  std::uint64_t server_rejected = 0;
  std::uint64_t server_restarts = 0;
  std::string server_gain_clamp;  // the server's limit event: it clamped this session's K_ps
  // ownership of the slave (docs/topics.md, "Ownership")
  std::uint64_t issued_before_owning = 0;  // commands sent while another master owned the slave
  bool refused = false;                    // refused the slave and never got it (exit status 4)
  bool refused_first = false;              // refused before it first owned the slave
  double waited_for_owner_s = 0.0;         // time spent refused, waiting for the slave
  std::uint64_t closing_cycles = 0;        // cycles of the final fade-out (after --samples)
  std::uint64_t releases_sent = 0;         // release commands written at the very end
  std::string owner_message;               // the server's word on who owns the slave
  // the loop's writes, handed to network threads (common/dds/async_writer.hpp)
  std::uint64_t commands_dropped = 0;  // replaced by a newer one (the network thread behind)
  std::uint64_t command_write_failures = 0;
  std::uint64_t states_replaced = 0;  // MasterState samples replaced by a newer one unwritten
  std::uint64_t events_dropped = 0;   // events that found the event ring full
  std::uint64_t write_failures = 0;   // refused by the middleware (states, events, device, tuning)
  // the device's silences (MasterCycle): the slave held, the cycles are not in the figures
  std::uint64_t driver_silences = 0;
  double driver_silent_s = 0.0;
  std::uint64_t experiment_writes = 0;  // teleop/experiment descriptions written
};

/// The live-tuning endpoint's counts over the session (TuningEndpoint).
struct TuningCounts {
  bool accepting = false;  ///< the master applies tuning requests (--accept-tuning)
  std::uint64_t received = 0;
  std::uint64_t ignored = 0;
  std::uint64_t dropped = 0;
};

/// What the report tells besides the session's figures: the options the master ran with, who it
/// is, which server it believed and the scene it began with.
struct ReportContext {
  const MasterOptions& options;
  const ServerBinding& binding;
  const SceneDescription& scene;  ///< the scene as the session began (empty if none came)
  std::uint32_t master_session = 0;
  std::uint64_t device_samples_ignored = 0;  ///< teleop/device_state samples of a second driver
  TuningCounts tuning;
};

/// The link's figures of a session, as the verdict judges them.
LinkCounts link_counts(const SessionReport& rep);

/// The session's verdict (client/metrics/link_verdict.hpp): the loop's, or "degraded" when the
/// link did not carry a loop that stayed stable; "refused" (exit status 4) when it never had the
/// slave (nothing was judged).
SessionVerdict session_verdict(const SessionMetrics& m, const SessionReport& rep,
                               const std::string& scheme);

/// Hertz for the scene's first deformable body with a material, at the deepest travel (invalid
/// when the scene has none).
HertzReference hertz_for_session(const SceneDescription& scene, const SessionMetrics& metrics);

/// The JSON summary: one object, its keys in a fixed order.
OrderedJson session_summary_json(const MasterCycle& cycle, const SessionReport& rep,
                                 const ReportContext& ctx);
/// session_summary_json() written to `path` (json_document). @throws std::runtime_error naming
/// the file when it cannot be written.
void write_session_summary_json(const std::string& path, const MasterCycle& cycle,
                                const SessionReport& rep, const ReportContext& ctx);

/// The printout: "session summary (...)" and one line per subject, "n/a" where the JSON has null.
std::string session_summary_text(const MasterCycle& cycle, const SessionReport& rep,
                                 const ReportContext& ctx);

/// The per-cycle CSV log: one row per cycle (homing, session and closing), 38 columns.
class CycleLog {
 public:
  static constexpr std::size_t kColumns = 38;
  /// Opens `path` and writes the header. `delay_injected_ms`: the injected forward plus backward
  /// delay every row carries [ms]. @throws std::runtime_error naming the file.
  CycleLog(const std::string& path, double delay_injected_ms);
  /// One row of the cycle that just finished, without allocating. `t_s`: since the loop began
  /// [s]; `loop_delay_ms`: the newest loop delay (NaN when none) [ms].
  void row(const MasterCycle& cycle, double t_s, double rtt_ms, double loop_delay_ms);
  /// Flushes and closes the file. @throws std::runtime_error naming the file when a write failed.
  void close() { csv_.close(); }

 private:
  CsvWriter csv_;
  double delay_injected_ms_;
};

}  // namespace teleop::master
