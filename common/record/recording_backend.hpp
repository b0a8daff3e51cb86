#pragma once
// The two sides of a recording format behind RecordingWriter and RecordingReader
// (recording.hpp): sqlite_recording.hpp and mcap_recording.hpp implement them.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "common/record/recording.hpp"

namespace teleop::record {

class WriterBackend {
 public:
  virtual ~WriterBackend() = default;
  virtual int add_topic(const std::string& name, const std::string& type_name,
                        const std::string& qos, const std::string& schema) = 0;
  virtual void set_meta(const std::string& key, const std::string& value) = 0;
  virtual void append(const std::vector<RecordedSample>& samples) = 0;
  virtual std::uint64_t raw_bytes() const = 0;
  virtual std::uint64_t stored_bytes() const = 0;
  virtual std::uint64_t samples_in_file() const = 0;
  virtual void close() = 0;
};

class ReaderBackend {
 public:
  virtual ~ReaderBackend() = default;
  virtual const std::vector<TopicRecord>& topics() const = 0;
  virtual std::map<std::string, std::string> meta() const = 0;
  virtual std::map<int, std::int64_t> counts() const = 0;
  virtual std::int64_t first_ns() const = 0;
  virtual std::int64_t last_ns() const = 0;
  virtual RecordingHealth health() const = 0;
  virtual std::string verify_file() = 0;
  virtual void scan(std::int64_t from_ns, std::int64_t to_ns,
                    const std::vector<int>& topic_ids) = 0;
  virtual bool next(RecordedSample& out) = 0;
};

}  // namespace teleop::record
