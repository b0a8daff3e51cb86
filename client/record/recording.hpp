#pragma once
// A recording of a session: one SQLite file (libsqlite3) holding every sample's serialized
// payload, its topic, its source timestamp (the writer's clock) and its receive timestamp (the
// recorder's clock), the writer's GUID and sequence number, indexed by receive time for seek.
// Payloads of 512 bytes or more (mesh frames, scene, topology) are zstd-compressed (libzstd).
//
//   CREATE TABLE meta(key TEXT PRIMARY KEY, value TEXT)
//   CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT UNIQUE, type_name TEXT, qos TEXT)
//   CREATE TABLE samples(topic_id INTEGER, receive_ns INTEGER, source_ns INTEGER,
//                        writer_guid BLOB, writer_seq INTEGER, codec INTEGER,
//                        raw_size INTEGER, data BLOB)          -- codec 0 raw, 1 zstd
//   CREATE INDEX samples_by_time ON samples(receive_ns)
//
// Timestamps are nanoseconds since the Unix epoch (Fast DDS stamps samples with the system
// clock). Any SQLite client can read the file; `sqlite3 FILE 'select ...'` works.
#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

struct sqlite3;
struct sqlite3_stmt;

namespace teleop::record {

class RecordingError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One recorded sample.
struct RecordedSample {
  int topic_id = 0;
  std::int64_t receive_ns = 0;  ///< when the recorder received it (system clock) [ns]
  std::int64_t source_ns = 0;   ///< when the writer wrote it (its system clock) [ns]
  std::uint8_t writer_guid[16] = {};
  std::int64_t writer_seq = 0;        ///< the writer's DDS sequence number
  std::vector<std::uint8_t> payload;  ///< serialized CDR payload with encapsulation header
};

struct TopicRecord {
  int id = 0;
  std::string name;
  std::string type_name;
  std::string qos;  ///< topic_table.hpp qos_name()
};

/// Writes a recording. Not thread-safe: one thread appends.
class RecordingWriter {
 public:
  /// Creates (or truncates) `path`. @throws RecordingError.
  explicit RecordingWriter(const std::string& path);
  ~RecordingWriter();
  RecordingWriter(const RecordingWriter&) = delete;
  RecordingWriter& operator=(const RecordingWriter&) = delete;

  /// Declares a topic; returns its id.
  int add_topic(const std::string& name, const std::string& type_name, const std::string& qos);
  void set_meta(const std::string& key, const std::string& value);
  /// Appends samples in one transaction.
  void append(const std::vector<RecordedSample>& samples);
  /// Bytes stored before / after compression so far.
  std::uint64_t raw_bytes() const { return raw_bytes_; }
  std::uint64_t stored_bytes() const { return stored_bytes_; }
  /// Commits and closes (also done by the destructor).
  void close();

 private:
  void exec(const std::string& sql);
  sqlite3* db_ = nullptr;
  sqlite3_stmt* insert_ = nullptr;
  std::vector<std::uint8_t> zbuf_;
  std::uint64_t raw_bytes_ = 0;
  std::uint64_t stored_bytes_ = 0;
};

/// Largest payload a recorded sample may declare (raw_size) [bytes]; a level-6 mesh frame is
/// under 1 MB.
constexpr std::int64_t kMaxSampleBytes = std::int64_t{64} << 20;
/// Longest span of receive times a recording may have [ns] (30 days).
constexpr std::int64_t kMaxRecordingSpanNs = std::int64_t{30} * 86400 * 1000000000;

/// Reads a recording. What is read from the file is checked before use: a FIFO or device is
/// refused at open, negative receive times or a span above kMaxRecordingSpanNs at open, a
/// sample's raw_size outside [0, kMaxSampleBytes] (or a raw sample whose size is not its
/// raw_size) when it is read; each is a config::ConfigError naming the file and the value.
class RecordingReader {
 public:
  /// Opens `path` read-only. @throws RecordingError if it is not a recording,
  /// config::ConfigError if it is not a regular file or its times are out of range.
  explicit RecordingReader(const std::string& path);
  ~RecordingReader();
  RecordingReader(const RecordingReader&) = delete;
  RecordingReader& operator=(const RecordingReader&) = delete;

  const std::vector<TopicRecord>& topics() const { return topics_; }
  std::map<std::string, std::string> meta() const;
  /// Samples per topic id.
  std::map<int, std::int64_t> counts() const;
  /// First and last receive time [ns]; both 0 for an empty recording.
  std::int64_t first_ns() const { return first_ns_; }
  std::int64_t last_ns() const { return last_ns_; }

  /// Starts a scan of the samples with receive time >= from_ns (and < to_ns if to_ns > 0), in
  /// receive order, optionally of the given topic ids only (empty: all).
  void scan(std::int64_t from_ns, std::int64_t to_ns = 0, const std::vector<int>& topic_ids = {});
  /// Next sample of the scan; false at the end. @throws config::ConfigError for a sample whose
  /// sizes are out of range, RecordingError for one that does not decompress.
  bool next(RecordedSample& out);
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  sqlite3* db_ = nullptr;
  sqlite3_stmt* scan_ = nullptr;
  std::vector<TopicRecord> topics_;
  std::int64_t first_ns_ = 0, last_ns_ = 0;
};

}  // namespace teleop::record
