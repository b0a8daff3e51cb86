#pragma once
// The MCAP recording format (recording.hpp) on top of mcap_writer.hpp and mcap_reader.hpp:
// topics are channels (message encoding `cdr`, metadata `qos`), types are schemas (`omgidl`,
// the IDL text), samples are messages (log_time = receive time, publish_time = source time,
// sequence = the writer's sequence number, low 32 bits; the writer's GUID in a kOpWriter
// record). Metadata set with set_meta() is written as a Metadata record named
// kMetadataName at the next append() and at close(); a reader merges them in file order.
#include <map>
#include <string>
#include <vector>

#include "common/record/mcap_reader.hpp"
#include "common/record/mcap_writer.hpp"
#include "common/record/recording_backend.hpp"

namespace teleop::record {

inline constexpr const char* kMetadataName = "teleop_record";

class McapRecordingWriter : public WriterBackend {
 public:
  McapRecordingWriter(const std::string& path, const McapOptions& options);
  int add_topic(const std::string& name, const std::string& type_name, const std::string& qos,
                const std::string& schema) override;
  void set_meta(const std::string& key, const std::string& value) override;
  void append(const std::vector<RecordedSample>& samples) override;
  std::uint64_t raw_bytes() const override { return writer_.message_bytes(); }
  std::uint64_t stored_bytes() const override { return writer_.file_bytes(); }
  std::uint64_t samples_in_file() const override { return writer_.messages_in_file(); }
  void close() override;

 private:
  void write_meta();
  mcap::Writer writer_;
  std::map<std::string, std::uint16_t> schema_ids_;  // by type name
  std::map<std::string, std::string> meta_;
  bool meta_dirty_ = false;
};

class McapRecordingReader : public ReaderBackend {
 public:
  explicit McapRecordingReader(const std::string& path);
  const std::vector<TopicRecord>& topics() const override { return topics_; }
  std::map<std::string, std::string> meta() const override;
  std::map<int, std::int64_t> counts() const override;
  std::int64_t first_ns() const override { return first_ns_; }
  std::int64_t last_ns() const override { return last_ns_; }
  RecordingHealth health() const override;
  std::string verify_file() override { return reader_.verify_data_crc(); }
  void scan(std::int64_t from_ns, std::int64_t to_ns, const std::vector<int>& topic_ids) override;
  bool next(RecordedSample& out) override;

 private:
  std::string path_;
  mutable mcap::Reader reader_;
  std::vector<TopicRecord> topics_;
  std::int64_t first_ns_ = 0, last_ns_ = 0;
};

}  // namespace teleop::record
