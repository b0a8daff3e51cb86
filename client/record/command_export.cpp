#include "client/record/command_export.hpp"

#include <vector>

#include "client/record/recording.hpp"
#include "common/dds/endpoint.hpp"
#include "common/util/command_stream.hpp"

namespace teleop::record {

std::size_t export_command_stream(const std::string& recording, const std::string& out) {
  RecordingReader reader(recording);
  int topic = -1;
  for (const TopicRecord& t : reader.topics()) {
    if (t.name == dds::topics::kMasterCommand) topic = t.id;
  }
  if (topic < 0) {
    throw RecordingError(recording + ": has no " + std::string(dds::topics::kMasterCommand) +
                         " samples (was the recorder told to --exclude it?)");
  }
  std::vector<StreamedCommand> rows;
  reader.scan(0, 0, {topic});
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
    throw RecordingError(recording + ": " + std::string(dds::topics::kMasterCommand) +
                         " was recorded but holds no samples");
  }
  write_command_stream(out, rows);
  return rows.size();
}

}  // namespace teleop::record
