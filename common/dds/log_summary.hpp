#pragma once
// Fast DDS's own error lines, counted and summarized.
//
// Fast DDS 2.9 logs one line per dropped sample for some drops: a sample larger than the
// reader's type allows ("Change payload size of 'N' bytes is larger than the history payload
// size ...", category RTPS_READER_HISTORY) prints a line each time, so a hostile writer could
// fill a log. install_log_summary() replaces Fast DDS's console output: the first line of each
// kind (category and message with its numbers blanked) is printed to stderr at once; repeats
// are counted and printed as one line with their count at most every kRepeatReportS seconds,
// and at exit (flush_log_summary). Oversized samples are also counted for the programs'
// statistics (the line names no topic: the count is the process's).
#include <cstdint>
#include <string>

namespace teleop::dds {

/// Seconds between two lines reporting repeats of one kind of Fast DDS error.
inline constexpr double kRepeatReportS = 10.0;

/// Replaces Fast DDS's console consumer with the summarizing one (once per process; later
/// calls do nothing). Called by every dds::Participant.
void install_log_summary();

/// Samples Fast DDS dropped as larger than the reader's type allows, since the start.
std::uint64_t oversized_samples();

/// Fast DDS error and warning lines seen since the start (each repeat counted).
std::uint64_t fastdds_log_entries();

/// Waits for Fast DDS's log thread, then prints the repeats not yet reported.
void flush_log_summary();

/// The kind under which a Fast DDS log line is counted: its category and its message with
/// every run of digits replaced by '#' (so the same drop with another size is one kind).
std::string log_kind(const std::string& category, const std::string& message);

/// True when a Fast DDS log line reports a sample dropped as too large for the reader.
bool is_oversized_sample_line(const std::string& category, const std::string& message);

}  // namespace teleop::dds
