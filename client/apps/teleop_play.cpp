// teleop_play: publishes a recording made by teleop_record back on a DDS domain, so
// teleop_monitor and teleop_viewer watch it as if it were live.
//
//   teleop_play FILE [--speed 1] [--seek S] [--domain D] [--profile P]
//                    [--exclude TOPIC]... [--wait 0.5] [--linger 1] [--quiet]
//                    [--progress | --no-progress]
//   teleop_play FILE --export-commands STREAM.csv
//   teleop_play FILE --info
//   teleop_play FILE --convert OUT
//
// FILE is an MCAP or an SQLite recording (told apart by its first bytes). An MCAP file is read
// through its summary, seeking by its chunk index; one whose recorder was killed (no summary)
// is recovered: every complete chunk whose CRC checks is played, and --info says what was
// dropped.
//
// Each topic is published with the QoS class it was recorded with (latched topics stay
// transient local for late observers), each sample byte for byte as it was received, paced by
// the recorded receive times divided by --speed. --seek starts that far into the recording,
// after publishing the latched topics (scene, mesh topology, events) recorded before it.
// It also publishes teleop/master_command: play on a domain with no live server, or pass
// --exclude teleop/master_command.
//
// --export-commands writes the recording's master commands as a command stream for the
// server's off-line re-simulation (`teleop_experiment resim`, docs/tools.md) and publishes
// nothing. --info reads every sample (CRCs, sizes) and prints what the file holds and how it
// was read. --convert writes the recording in the other format (by OUT's extension: SQLite for
// .db, .sqlite, .sqlite3, else MCAP).
//
// Exit status: 0 done, 2 bad command line (or --seek past the end), 1 runtime failure.
#include <CLI/CLI.hpp>
#include <iostream>
#include <optional>

#include "client/record/info.hpp"
#include "client/record/player.hpp"
#include "client/record/topic_table.hpp"
#include "common/config/config.hpp"
#include "common/config/flags.hpp"
#include "common/dds/network_flags.hpp"
#include "common/record/commands.hpp"
#include "common/record/convert.hpp"
#include "common/record/recording.hpp"
#include "common/util/files.hpp"
#include "common/util/progress.hpp"
#include "common/util/signals.hpp"

namespace {

/// teleop_play's command line.
struct Flags {
  std::optional<int> domain;
  std::optional<std::string> profile;
  teleop::record::PlayerOptions po;
  teleop::dds::NetworkFlags net_flags;
  bool progress = false;
  bool no_progress = false;
  std::string export_commands;
  bool info = false;
  std::string convert;
};

/// Declares every flag of teleop_play.
void add_flags(CLI::App& app, Flags& f) {
  teleop::record::PlayerOptions& po = f.po;
  app.add_option("file", po.file, "recording made by teleop_record")->required();
  using teleop::config::add_integer;
  using teleop::config::add_number;
  add_number(app, "--speed", po.speed, 0.01, 100.0, "playback speed (1 = as recorded)")
      ->capture_default_str();
  add_number(app, "--seek", po.seek_s, 0.0, 1e9,
             "start this far into the recording, at most its length", "s");
  add_integer(app, "--domain", f.domain, 0.0, 232.0,
              "DDS domain id (default: $TELEOP_DOMAIN or 0)");
  app.add_option("--profile", f.profile,
                 "Fast DDS profile name in deploy/profiles or XML path (default: loopback)");
  teleop::dds::add_network_flags(app, f.net_flags, "observer");
  app.add_option("--exclude", po.exclude, "topic not to publish (repeatable)");
  add_number(app, "--wait", po.wait_s, 0.0, 60.0, "pause before the first sample, for discovery",
             "s")
      ->capture_default_str();
  add_number(app, "--linger", po.linger_s, 0.0, 3600.0,
             "keep publishing latched topics after the end", "s")
      ->capture_default_str();
  add_number(app, "--max-gap", po.max_gap_s, 0.001, 3600.0,
             "a pause longer than this between recorded samples is cut to it, with a message", "s")
      ->capture_default_str();
  app.add_flag("--quiet", po.quiet, "print only warnings and errors");
  app.add_flag("--progress", f.progress,
               "the progress line on stderr even when it is not a terminal");
  app.add_flag("--no-progress", f.no_progress, "no progress line");
  app.add_option("--export-commands", f.export_commands,
                 "write the recorded master commands to this command stream (CSV) for "
                 "`teleop_experiment resim`, publish nothing");
  app.add_flag("--info", f.info,
               "read every sample, print what the file holds and how it was read, publish "
               "nothing");
  app.add_option("--convert", f.convert,
                 "write the recording to this file in the other format (SQLite for .db, "
                 ".sqlite, .sqlite3, else MCAP), publish nothing");
}

/// The excluded topics, the recording and the output files (the ranges were checked on the
/// flags' text). @throws teleop::config::ConfigError naming the flag, the value and what is
/// allowed.
void check_flags(const Flags& f) {
  using namespace teleop;
  const record::PlayerOptions& po = f.po;
  for (const auto& t : po.exclude) {
    if (!record::find_topic(t)) {
      std::string names;
      for (const auto& e : record::known_topics()) names += (names.empty() ? "" : ", ") + e.name;
      throw config::ConfigError("command line: --exclude '" + t +
                                "' is not a known topic (allowed: " + names + ")");
    }
  }
  config::require_regular_file(po.file, "recording");
  if (!f.convert.empty()) prepare_output_file("--convert", f.convert);
  if (!f.export_commands.empty()) prepare_output_file("--export-commands", f.export_commands);
}

/// --info, --convert or --export-commands: the file read and nothing published. Returns the exit
/// status, or -1 when none of them was asked for.
int run_offline(const Flags& f) {
  using namespace teleop;
  const record::PlayerOptions& po = f.po;
  if (f.info) {
    std::cout << record::recording_info(po.file);
    return 0;
  }
  if (!f.convert.empty()) {
    const auto n =
        record::convert_recording(po.file, f.convert, record::format_for_path(f.convert));
    if (!po.quiet) {
      std::cout << "teleop_play: " << n << " samples -> " << f.convert << " ("
                << record::format_name(record::format_for_path(f.convert)) << ")\n";
    }
    return 0;
  }
  if (!f.export_commands.empty()) {
    const std::size_t n = record::export_command_stream(po.file, f.export_commands);
    if (!po.quiet)
      std::cout << "teleop_play: " << n << " commands -> " << f.export_commands << "\n";
    return 0;
  }
  return -1;
}

/// Publishes the recording on the domain. Returns the exit status.
int play(Flags& f) {
  using namespace teleop;
  record::PlayerOptions& po = f.po;
  const auto opts =
      teleop::dds::resolve_participant_options(f.profile, f.domain, "teleop_play", f.net_flags);
  teleop::dds::profile_file(opts.profile);
  install_stop_signal_handlers();
  { record::RecordingReader check(po.file); }  // a bad file fails before DDS starts
  teleop::dds::Participant p(opts);
  set_progress_mode(progress_mode_from(f.progress, f.no_progress, po.quiet));
  po.progress = progress_stream();
  const auto r = record::play(p, po);
  return r.failures == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"teleop_play: publish a recorded session back on a DDS domain"};
  Flags f;
  add_flags(app, f);
  if (const int status = teleop::config::parse_command_line(app, "teleop_play", argc, argv);
      status >= 0) {
    return status == 2 ? 2 : status;
  }
  try {
    check_flags(f);
    if (const int status = run_offline(f); status >= 0) return status;
    return play(f);
  } catch (const teleop::config::ConfigError& e) {
    std::cerr << "teleop_play: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "teleop_play: error: " << e.what() << "\n";
    return 1;
  }
}
