// teleop_record: records every teleop/* topic of a session into one indexed file.
//
//   teleop_record --out session.mcap [--format mcap|sqlite] [--duration S] [--domain D]
//                 [--profile P] [--queue-mb 64] [--batch-ms 10] [--chunk-mb 1] [--chunk-s 1]
//                 [--exclude TOPIC]... [--summary-json FILE] [--quiet]
//                 [--progress | --no-progress]
//
// Each sample is stored as the serialized CDR payload its writer sent, with the writer's
// source timestamp, the recorder's receive timestamp, the writer's GUID and sequence number
// (common/record/recording.hpp). The format is MCAP unless --out ends in .db, .sqlite or
// .sqlite3 (SQLite) or --format says otherwise: one schema per type (the IDL text), one
// channel per topic, zstd chunks closed every --chunk-mb of samples or --chunk-s seconds,
// whichever comes first, a chunk index and a summary; Foxglove and Lichtblick open it as it is.
// It only subscribes, with the QoS class of each topic's live writers, so it never slows the
// loop. Memory is bounded by --queue-mb; samples dropped because the queue was full, and
// samples lost before they reached the recorder (gaps in a writer's sequence numbers), are
// counted and printed at the end.
//
// Killed with -9, an MCAP recording keeps every chunk already written: what is lost is the open
// chunk (at most --chunk-s seconds of samples) and the queue (--batch-ms plus up to 50 ms).
// A file that cannot be written (a full disk) stops the recording: an MCAP file is closed as a
// valid file holding its complete chunks, an SQLite file keeps every committed sample; the
// recorder says how many and exits 1.
//
// Exit status (docs/exit_codes.md): 0 done, 1 runtime failure (file, DDS, a full disk), 2 bad
// command line or output path, 3 nothing recorded (no sample arrived on any topic).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <optional>
#include <thread>

#include "client/record/recorder.hpp"
#include "client/record/topic_table.hpp"
#include "common/config/config.hpp"
#include "common/config/flags.hpp"
#include "common/dds/network_flags.hpp"
#include "common/record/recording.hpp"
#include "common/util/clock.hpp"
#include "common/util/exit_codes.hpp"
#include "common/util/files.hpp"
#include "common/util/progress.hpp"
#include "common/util/signals.hpp"

namespace {

using namespace teleop;

/// Checks the flags that need more than a range (checked on their text) and fills `ro` from
/// them. @throws config::ConfigError naming the flag, its value and what is allowed.
void check_options(record::RecorderOptions& ro, const std::string& format, double queue_mb,
                   double chunk_mb, double chunk_s) {
  for (const auto& t : ro.exclude) {
    if (!record::find_topic(t)) {
      std::string names;
      for (const auto& e : record::known_topics()) names += (names.empty() ? "" : ", ") + e.name;
      throw config::ConfigError("command line: --exclude '" + t +
                                "' is not a known topic (allowed: " + names + ")");
    }
  }
  ro.queue_bytes = static_cast<std::size_t>(queue_mb * 1024.0 * 1024.0);
  ro.mcap.chunk_bytes = static_cast<std::uint64_t>(chunk_mb * 1024.0 * 1024.0);
  ro.mcap.chunk_ns = static_cast<std::int64_t>(chunk_s * 1e9);
  const record::RecordingFormat by_name = record::format_for_path(ro.out);
  ro.format = format.empty() ? by_name : record::parse_format("--format", format);
  const bool mcap_name = ro.out.size() > 5 && ro.out.substr(ro.out.size() - 5) == ".mcap";
  if ((*ro.format == record::RecordingFormat::kMcap && by_name != *ro.format) ||
      (*ro.format == record::RecordingFormat::kSqlite && mcap_name)) {
    throw config::ConfigError(
        "command line: --format " + format + " does not match the extension of --out '" + ro.out +
        "' (.mcap: mcap; .db, .sqlite, .sqlite3: sqlite); rename the file or leave "
        "--format out");
  }
}

/// Prints what was recorded (or the failure), writes --summary-json; returns the exit status.
int report(const record::Recorder& recorder, const std::string& out, bool quiet,
           const std::string& summary_json) {
  if (recorder.failed()) {
    // a full disk: the file keeps every sample written before the failure (MCAP: a valid file
    // of its complete chunks)
    std::fprintf(stderr,
                 "teleop_record: error: %s\nteleop_record: %s holds the %llu samples written "
                 "before the failure; %llu later samples were not written\n",
                 recorder.error().c_str(), out.c_str(),
                 static_cast<unsigned long long>(recorder.written()),
                 static_cast<unsigned long long>(recorder.lost_after_failure()));
    if (!summary_json.empty()) write_text_file(summary_json, recorder.summary_json() + "\n");
    return 1;
  }
  if (!quiet) {
    std::printf("teleop_record: %llu samples, %.1f MB of payload stored in %.1f MB\n",
                static_cast<unsigned long long>(recorder.samples()),
                static_cast<double>(recorder.raw_bytes()) / 1e6,
                static_cast<double>(recorder.stored_bytes()) / 1e6);
    for (const auto& c : recorder.counts()) {
      if (c.samples == 0 && c.dropped == 0) continue;
      std::printf(
          "  %-24s %8llu samples  %3llu writers  %llu lost  %llu dropped\n", c.name.c_str(),
          static_cast<unsigned long long>(c.samples), static_cast<unsigned long long>(c.writers),
          static_cast<unsigned long long>(c.gaps), static_cast<unsigned long long>(c.dropped));
    }
  }
  if (!summary_json.empty()) write_text_file(summary_json, recorder.summary_json() + "\n");
  if (recorder.samples() == 0) {
    std::fprintf(stderr,
                 "teleop_record: nothing was recorded: no sample arrived on any topic (is a "
                 "server or master running on this domain and profile?); %s holds no sample\n",
                 out.c_str());
    return exit_code::kNoPeer;
  }
  return exit_code::kOk;
}

/// teleop_record's command line.
struct Flags {
  std::optional<int> domain;
  std::optional<std::string> profile;
  record::RecorderOptions ro;
  double duration_s = 0.0;
  double queue_mb = 64.0;
  std::string summary_json;
  bool quiet = false, progress = false, no_progress = false;
  std::string format;
  double chunk_mb = 1.0, chunk_s = 1.0;
  teleop::dds::NetworkFlags net_flags;
};

/// Declares every flag of teleop_record.
void add_flags(CLI::App& app, Flags& f) {
  record::RecorderOptions& ro = f.ro;
  app.add_option("--out", ro.out,
                 "recording file, created or replaced (MCAP; SQLite for .db, .sqlite, .sqlite3)")
      ->required();
  app.add_option("--format", f.format,
                 "mcap or sqlite (default: from the --out extension, mcap for any other name)");
  config::add_number(app, "--chunk-mb", f.chunk_mb, 0.0625, 64.0,
                     "MCAP: close a chunk at this many MiB of samples", "MiB")
      ->capture_default_str();
  config::add_number(app, "--chunk-s", f.chunk_s, 0.05, 60.0,
                     "MCAP: close a chunk this long after its first sample (a recorder killed "
                     "with -9 loses at most this much)",
                     "s")
      ->capture_default_str();
  config::add_number(app, "--duration", f.duration_s, 0.0, 1e6,
                     "stop after this long (0 = until SIGINT)", "s");
  config::add_integer(app, "--domain", f.domain, 0.0, 232.0,
                      "DDS domain id (default: $TELEOP_DOMAIN or 0)");
  app.add_option("--profile", f.profile,
                 "Fast DDS profile name in deploy/profiles or XML path (default: loopback)");
  teleop::dds::add_network_flags(app, f.net_flags, "observer");
  config::add_number(app, "--queue-mb", f.queue_mb, 1.0, 4096.0, "bound of the in-memory queue",
                     "MiB")
      ->capture_default_str();
  app.add_option("--exclude", ro.exclude, "topic not to record (repeatable)");
  config::add_number(app, "--batch-ms", ro.batch_ms, 0.0, 50.0,
                     "take samples in batches this far apart (0 = wake per sample)", "ms")
      ->capture_default_str();
  app.add_option("--summary-json", f.summary_json, "write the counts as JSON here at exit");
  app.add_flag("--quiet", f.quiet, "print only warnings and errors");
  app.add_flag("--progress", f.progress,
               "with --duration: the time line on stderr even when it is not a terminal");
  app.add_flag("--no-progress", f.no_progress, "no time line on stderr");
}

/// Records until --duration, a stop signal or a failure; returns the exit status (report()).
int record_session(Flags& f) {
  record::RecorderOptions& ro = f.ro;
  check_options(ro, f.format, f.queue_mb, f.chunk_mb, f.chunk_s);
  prepare_output_file("--out", ro.out);
  if (!f.summary_json.empty()) prepare_output_file("--summary-json", f.summary_json);
  const auto opts =
      teleop::dds::resolve_participant_options(f.profile, f.domain, "teleop_record", f.net_flags);
  teleop::dds::profile_file(opts.profile);
  install_stop_signal_handlers();
  teleop::dds::Participant p(opts);
  record::Recorder recorder(p, ro);
  if (!f.quiet) {
    std::printf("teleop_record: recording %zu topics on domain %d (profile %s) to %s (%s)\n",
                record::known_topics().size() - ro.exclude.size(), opts.domain,
                opts.profile.c_str(), ro.out.c_str(), record::format_name(*ro.format));
    std::fflush(stdout);
  }
  set_progress_mode(progress_mode_from(f.progress, f.no_progress, f.quiet));
  // the time line: only for a recording of known length
  const double duration_s = f.duration_s;
  Progress line(duration_s > 0.0 ? progress_stream() : nullptr, "teleop_record", duration_s, "s",
                1);
  const auto t0 = now_ns();
  while (!stop_requested() && !recorder.failed()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    line.set(std::min(duration_s, seconds_between(t0, now_ns())));
    if (duration_s > 0.0 && seconds_between(t0, now_ns()) >= duration_s) break;
  }
  line.finish();
  recorder.stop();
  return report(recorder, ro.out, f.quiet, f.summary_json);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"teleop_record: record every topic of a teleoperation session"};
  Flags f;
  add_flags(app, f);
  if (const int status = teleop::config::parse_command_line(app, "teleop_record", argc, argv);
      status >= 0) {
    return status == 2 ? 2 : status;
  }
  try {
    return record_session(f);
  } catch (const teleop::config::ConfigError& e) {
    std::cerr << "teleop_record: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "teleop_record: error: " << e.what() << "\n";
    return 1;
  }
}
