#include "common/record/commands.hpp"

#include <cmath>
#include <cstdio>

#include "common/config/config.hpp"
#include "common/dds/endpoint.hpp"
#include "common/record/recording.hpp"

namespace teleop::record {

std::vector<StreamedCommand> recorded_commands(const std::string& recording, double from_s,
                                               double to_s) {
  RecordingReader reader(recording);
  int topic = -1;
  for (const TopicRecord& t : reader.topics()) {
    if (t.name == dds::topics::kMasterCommand.name) topic = t.id;
  }
  if (topic < 0) {
    throw RecordingError(recording + ": has no " + std::string(dds::topics::kMasterCommand.name) +
                         " samples (was the recorder told to --exclude it?)");
  }
  const double length_s = static_cast<double>(reader.last_ns() - reader.first_ns()) * 1e-9;
  if (from_s > length_s) {
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "command line: --from %g is beyond the end of the recording (allowed: 0 to "
                  "%.3f s)",
                  from_s, length_s);
    throw config::ConfigError(buf);
  }
  const auto ns = [&](double s) {
    return reader.first_ns() + static_cast<std::int64_t>(std::llround(s * 1e9));
  };
  std::vector<StreamedCommand> rows;
  reader.scan(ns(from_s), to_s > 0.0 ? ns(to_s) : 0, {topic});
  RecordedSample s;
  while (reader.next(s)) {
    StreamedCommand c;
    c.receive_ns = s.receive_ns;
    c.source_ns = s.source_ns;
    c.writer = to_hex(s.writer_guid, sizeof(s.writer_guid));
    c.payload = s.payload;
    rows.push_back(std::move(c));
  }
  if (rows.empty()) {
    throw RecordingError(recording + ": " + std::string(dds::topics::kMasterCommand.name) +
                         " holds no samples" +
                         (from_s > 0.0 || to_s > 0.0 ? " in the window asked for" : ""));
  }
  return rows;
}

std::size_t export_command_stream(const std::string& recording, const std::string& out) {
  const std::vector<StreamedCommand> rows = recorded_commands(recording);
  write_command_stream(out, rows);
  return rows.size();
}

}  // namespace teleop::record
