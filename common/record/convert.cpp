#include "common/record/convert.hpp"

#include <map>
#include <vector>

namespace teleop::record {

std::uint64_t convert_recording(const std::string& in, const std::string& out,
                                RecordingFormat format) {
  RecordingReader reader(in);
  RecordingWriter writer(out, format);
  std::map<int, int> ids;  // topic id in `in` -> in `out`
  for (const TopicRecord& t : reader.topics()) {
    ids[t.id] = writer.add_topic(t.name, t.type_name, t.qos);
  }
  for (const auto& [k, v] : reader.meta()) {
    if (k != "format") writer.set_meta(k, v);
  }
  writer.set_meta("converted_from", in);
  std::vector<RecordedSample> batch(1000);
  std::size_t k = 0;
  std::uint64_t n = 0;
  reader.scan(reader.first_ns());
  while (reader.next(batch[k])) {
    batch[k].topic_id = ids.at(batch[k].topic_id);
    ++n;
    if (++k == batch.size()) {
      writer.append(batch);
      k = 0;
    }
  }
  batch.resize(k);
  writer.append(batch);
  writer.close();
  return n;
}

}  // namespace teleop::record
