// teleop_experiment resim --recording REC [--from S] [--to S] [--scene FILE] [--rate 1000]
//                         [--tail 0.5] --out DIR
// teleop_experiment resim --commands STREAM.csv [--scene FILE] [--rate 1000] [--tail 0.5]
//                         --out DIR
//
// Re-runs a session off-line from its recorded master commands through the server's cycle on a
// simulated clock (server/node/resim.hpp): the same commands and scene give the same states,
// forces and events on every run, and the printed hash says so. The commands come from a
// recording (MCAP or SQLite, common/record/commands.hpp; --from/--to pick a window in seconds
// from its first sample, and an MCAP file is read only from the chunks that overlap it, through
// its chunk index) or from a command stream (`teleop_play REC --export-commands STREAM.csv`).
// Writes resim_states.csv (one row per physics step), resim_events.csv and resim_summary.csv
// (counts and the hash). This is how a bad moment found in a recording is reproduced, inspected
// and, after a fix, checked.
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>

#include "common/config/config.hpp"
#include "common/record/commands.hpp"
#include "common/util/command_stream.hpp"
#include "common/util/csv.hpp"
#include "common/util/data_dir.hpp"
#include "common/util/registry.hpp"
#include "server/node/resim.hpp"
#include "server/world/world_model.hpp"

namespace {

using teleop::format_number;

/// A number option's value, or `fallback`; the value was checked against the option's range
/// (the registration at the end of this file) before the command runs.
double number_flag(const teleop::CommandArgs& args, const std::string& flag, const char* fallback) {
  return std::stod(args.option(flag, fallback));
}

/// A re-simulation steps the world through every gap between commands at the physics rate: a
/// gap longer than --max-gap (a clock jump, an edited file) is refused, not simulated for hours.
void check_gaps(const std::vector<teleop::StreamedCommand>& stream, const std::string& file,
                double max_gap_s) {
  for (std::size_t i = 1; i < stream.size(); ++i) {
    const double gap_s =
        static_cast<double>(stream[i].receive_ns - stream[i - 1].receive_ns) * 1e-9;
    if (gap_s > max_gap_s) {
      char what[200];
      std::snprintf(what, sizeof what,
                    ": line %zu, column 'receive_ns': %.3f s after the previous command; gaps "
                    "longer than --max-gap %g s are refused (allowed --max-gap: 0.001 to 3600 s)",
                    i + 2, gap_s, max_gap_s);
      throw teleop::config::ConfigError(file + what);
    }
  }
}

std::string hash_text(std::uint64_t h) {
  char buf[20];
  std::snprintf(buf, sizeof buf, "%016" PRIx64, h);
  return buf;
}

/// The commands of --recording (in the --from/--to window) or of --commands.
std::vector<teleop::StreamedCommand> resim_commands(const teleop::CommandArgs& args,
                                                    std::string& source) {
  const std::string commands = args.option("--commands", "");
  const std::string recording = args.option("--recording", "");
  if (commands.empty() == recording.empty()) {
    throw teleop::config::ConfigError(
        "command line: give exactly one of --recording REC (a recording made by teleop_record) "
        "and --commands STREAM.csv (teleop_play REC --export-commands STREAM.csv)");
  }
  const double from_s = number_flag(args, "--from", "0");
  const double to_s = number_flag(args, "--to", "0");
  if (!commands.empty()) {
    if (from_s > 0.0 || to_s > 0.0) {
      throw teleop::config::ConfigError(
          "command line: --from and --to apply to --recording only (a command stream is "
          "re-simulated whole)");
    }
    source = commands;
    return teleop::read_command_stream(commands);
  }
  if (to_s > 0.0 && to_s <= from_s) {
    throw teleop::config::ConfigError("command line: --to " + format_number(to_s) +
                                      " must be after --from " + format_number(from_s) +
                                      " (or 0: to the end)");
  }
  teleop::config::require_regular_file(recording, "recording");
  source = recording;
  return teleop::record::recorded_commands(recording, from_s, to_s);
}

int run_resim(const teleop::CommandArgs& args) {
  const std::string scene = args.option("--scene", teleop::data_path("scenes/default.yaml"));
  teleop::server::ResimOptions opt;
  opt.rate_hz = number_flag(args, "--rate", "1000");
  opt.tail_s = number_flag(args, "--tail", "0.5");
  const teleop::sim::WorldModel model = teleop::sim::load_world_model(scene);
  const double max_gap_s = number_flag(args, "--max-gap", "60");
  std::string commands;
  const auto stream = resim_commands(args, commands);
  check_gaps(stream, commands, max_gap_s);

  teleop::CsvWriter states(
      (args.out_dir / "resim_states.csv").string(),
      {"step", "sim_time_s", "command_seq", "holding", "tip_x_m", "tip_y_m", "tip_z_m", "force_x_n",
       "force_y_n", "force_z_n", "in_contact", "contact_object", "penetration_m", "deformation_m"});
  teleop::CsvWriter events((args.out_dir / "resim_events.csv").string(),
                           {"sim_time_s", "kind", "severity", "value", "message"});
  // progress in simulated time: the commands' span and the tail
  const double span_s =
      stream.empty()
          ? 0.0
          : static_cast<double>(stream.back().receive_ns - stream.front().receive_ns) * 1e-9;
  teleop::Progress progress("resim", span_s + opt.tail_s, "sim s", 1);
  const auto r = teleop::server::resimulate(
      model, stream, opt,
      [&](const teleop::server::ResimStep& s) {
        progress.set(s.sim_time_s);
        const auto& o = *s.out;
        states.row({static_cast<double>(s.step), s.sim_time_s, static_cast<double>(s.command_seq),
                    s.holding ? 1.0 : 0.0, o.tip_position_m.x(), o.tip_position_m.y(),
                    o.tip_position_m.z(), o.contact_force_n.x(), o.contact_force_n.y(),
                    o.contact_force_n.z(), o.in_contact ? 1.0 : 0.0,
                    static_cast<double>(o.contact_object), o.penetration_m, o.deformation_m});
      },
      [&](const teleop::sim::SimEvent& e) {
        events.row_text({format_number(e.sim_time_s), std::to_string(static_cast<int>(e.kind)),
                         std::to_string(static_cast<int>(e.severity)), format_number(e.value),
                         std::string("\"") + e.message + "\""});
      });
  progress.finish();
  states.close();
  events.close();
  teleop::CsvWriter summary((args.out_dir / "resim_summary.csv").string(), {"key", "value"});
  auto put = [&](const char* k, std::uint64_t v) { summary.row_text({k, std::to_string(v)}); };
  put("steps", r.steps);
  put("commands", r.commands);
  put("accepted", r.accepted);
  put("rejected_nan", r.rejected_nan);
  put("rejected_workspace", r.rejected_workspace);
  put("rejected_stale", r.rejected_stale);
  put("rejected_passivity", r.rejected_passivity);
  put("undecodable", r.undecodable);
  put("refused_owner", r.refused_owner);
  put("masters", r.masters);
  put("events", r.events);
  put("watchdog_trips", r.watchdog_trips);
  summary.row_text({"hash", hash_text(r.hash)});
  summary.close();
  std::printf("resim: %s on %s: %" PRIu64 " steps, %" PRIu64 " commands (%" PRIu64
              " accepted, %" PRIu64 " rejected, %" PRIu64 " undecodable, %" PRIu64
              " refused: not the owner) from %" PRIu64 " owner(s), %" PRIu64 " events, %" PRIu64
              " watchdog trips; hash %s\n",
              commands.c_str(), model.name.c_str(), r.steps, r.commands, r.accepted,
              r.rejected_nan + r.rejected_workspace + r.rejected_stale + r.rejected_passivity,
              r.undecodable, r.refused_owner, r.masters, r.events, r.watchdog_trips,
              hash_text(r.hash).c_str());
  return 0;
}

}  // namespace

TELEOP_REGISTER_COMMAND(
    experiments, "resim",
    "re-run a session off-line from its recorded commands (a recording, or "
    "teleop_play --export-commands), deterministic: states, events, a hash",
    run_resim, teleop::text_option("--recording", "recording (MCAP or SQLite)"),
    teleop::number_option("--from", 0, 1e6, "start this far into the recording [s]"),
    teleop::number_option("--to", 0, 1e6, "end this far into the recording [s], 0 = end"),
    teleop::text_option("--commands", "command stream CSV"),
    teleop::text_option("--scene", "scene YAML"),
    teleop::number_option("--rate", 10, 20000, "physics rate [Hz]"),
    teleop::number_option("--tail", 0, 60, "simulate after the last [s]"),
    teleop::number_option("--max-gap", 0.001, 3600, "longest gap between commands [s]"));
