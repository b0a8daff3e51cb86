#include "common/record/mcap_recording.hpp"

#include <algorithm>
#include <cstring>
#include <limits>

#include "common/config/config.hpp"
#include "common/util/version.hpp"
#include "idl/idl_text.hpp"

namespace teleop::record {

namespace {

mcap::WriterOptions writer_options(const McapOptions& o) {
  mcap::WriterOptions w;
  w.chunk_bytes = o.chunk_bytes;
  w.chunk_ns = o.chunk_ns;
  w.zstd_level = o.zstd_level;
  w.library = "teleop " + version_string();
  return w;
}

bool all_zero(const std::uint8_t* p, std::size_t n) {
  return std::all_of(p, p + n, [](std::uint8_t b) { return b == 0; });
}

}  // namespace

McapRecordingWriter::McapRecordingWriter(const std::string& path, const McapOptions& options)
    : writer_(path, writer_options(options)) {}

int McapRecordingWriter::add_topic(const std::string& name, const std::string& type_name,
                                   const std::string& qos, const std::string& schema) {
  auto it = schema_ids_.find(type_name);
  if (it == schema_ids_.end()) {
    const std::string text =
        schema.empty() ? std::string(idl::idl_text_for_type(type_name)) : schema;
    const std::uint16_t id = text.empty() ? 0 : writer_.add_schema(type_name, "omgidl", text);
    it = schema_ids_.emplace(type_name, id).first;
  }
  mcap::KeyValues metadata = {{"qos", qos}};
  // without a schema the type name would be lost: keep it beside the QoS
  if (it->second == 0) metadata.emplace_back("dds_type", type_name);
  return writer_.add_channel(it->second, name, "cdr", metadata);
}

void McapRecordingWriter::set_meta(const std::string& key, const std::string& value) {
  meta_[key] = value;
  meta_dirty_ = true;
}

void McapRecordingWriter::write_meta() {
  if (!meta_dirty_) return;
  meta_dirty_ = false;
  writer_.add_metadata(kMetadataName, mcap::KeyValues(meta_.begin(), meta_.end()));
}

void McapRecordingWriter::append(const std::vector<RecordedSample>& samples) {
  write_meta();
  for (const RecordedSample& s : samples) {
    writer_.add_message(
        static_cast<std::uint16_t>(s.topic_id), static_cast<std::uint32_t>(s.writer_seq),
        static_cast<std::uint64_t>(s.receive_ns), static_cast<std::uint64_t>(s.source_ns),
        s.payload.data(), s.payload.size(), all_zero(s.writer_guid, 16) ? nullptr : s.writer_guid);
  }
  writer_.tick();
}

void McapRecordingWriter::close() {
  if (writer_.failed()) return;
  write_meta();
  writer_.close();
}

McapRecordingReader::McapRecordingReader(const std::string& path) : path_(path), reader_(path) {
  for (const auto& [id, ch] : reader_.channels()) {
    TopicRecord t;
    t.id = id;
    t.name = ch.topic;
    t.qos = "stream";
    for (const auto& [k, v] : ch.metadata) {
      if (k == "qos") t.qos = v;
      if (k == "dds_type") t.type_name = v;
    }
    const auto s = reader_.schemas().find(ch.schema_id);
    if (s != reader_.schemas().end()) t.type_name = s->second.name;
    topics_.push_back(std::move(t));
  }
  constexpr auto kMax = static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max());
  const std::uint64_t first = reader_.start_ns(), last = reader_.end_ns();
  if (first > kMax || last > kMax ||
      last - first > static_cast<std::uint64_t>(kMaxRecordingSpanNs)) {
    throw config::ConfigError(path + ": field 'log_time': from " + std::to_string(first) + " to " +
                              std::to_string(last) +
                              " ns; receive times must be >= 0 (at most 2^63 - 1 ns) and span " +
                              "at most " + std::to_string(kMaxRecordingSpanNs / 1000000000) + " s");
  }
  first_ns_ = static_cast<std::int64_t>(first);
  last_ns_ = static_cast<std::int64_t>(last);
}

std::map<std::string, std::string> McapRecordingReader::meta() const {
  std::map<std::string, std::string> out;
  for (const mcap::MetadataInfo& m : reader_.metadata()) {
    for (const auto& [k, v] : m.entries) {
      out[m.name == kMetadataName ? k : m.name + "/" + k] = v;
    }
  }
  return out;
}

std::map<int, std::int64_t> McapRecordingReader::counts() const {
  std::map<int, std::int64_t> out;
  for (const auto& [id, n] : reader_.channel_counts()) out[id] = static_cast<std::int64_t>(n);
  return out;
}

RecordingHealth McapRecordingReader::health() const {
  const mcap::Health& h = reader_.health();
  RecordingHealth r;
  r.recovered = h.recovered;
  r.how = h.indexed ? "MCAP, read through its summary and chunk index"
                    : "MCAP, recovered by a scan of its data section";
  r.note = h.note;
  r.chunks = reader_.chunks().size();
  r.dropped_bytes = h.dropped_bytes;
  r.dropped_chunks = h.dropped_chunks;
  r.dropped_messages = h.dropped_messages;
  r.skipped_messages = h.skipped_messages;
  return r;
}

void McapRecordingReader::scan(std::int64_t from_ns, std::int64_t to_ns,
                               const std::vector<int>& topic_ids) {
  std::vector<std::uint16_t> channels;
  for (int id : topic_ids) {
    if (id > 0 && id <= 0xFFFF) channels.push_back(static_cast<std::uint16_t>(id));
  }
  if (channels.empty() && !topic_ids.empty()) {
    reader_.scan(1, 1, {});  // none of them can exist: an empty scan
    return;
  }
  reader_.scan(static_cast<std::uint64_t>(std::max<std::int64_t>(from_ns, 0)),
               static_cast<std::uint64_t>(std::max<std::int64_t>(to_ns, 0)), channels);
}

bool McapRecordingReader::next(RecordedSample& out) {
  mcap::MessageView m;
  if (!reader_.next(m)) return false;
  if (m.size > static_cast<std::size_t>(kMaxSampleBytes)) {
    throw config::ConfigError(path_ + ": a message of channel " + std::to_string(m.channel_id) +
                              " at log_time " + std::to_string(m.log_time_ns) + " holds " +
                              std::to_string(m.size) + " bytes; allowed range [0, " +
                              std::to_string(kMaxSampleBytes) + "]");
  }
  out.topic_id = m.channel_id;
  out.receive_ns = static_cast<std::int64_t>(m.log_time_ns);
  out.source_ns = static_cast<std::int64_t>(m.publish_time_ns);
  out.writer_seq = m.sequence;
  if (m.writer_guid) {
    std::memcpy(out.writer_guid, m.writer_guid, 16);
  } else {
    std::memset(out.writer_guid, 0, 16);
  }
  out.payload.assign(m.data, m.data + m.size);
  return true;
}

}  // namespace teleop::record
