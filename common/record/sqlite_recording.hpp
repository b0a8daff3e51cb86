#pragma once
// The SQLite recording format (recording.hpp): one SQLite file (libsqlite3), zstd for payloads
// of 512 bytes or more (mesh frames, scene, topology), indexed by receive time for seek.
//
//   CREATE TABLE meta(key TEXT PRIMARY KEY, value TEXT)
//   CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT UNIQUE, type_name TEXT, qos TEXT)
//   CREATE TABLE samples(topic_id INTEGER, receive_ns INTEGER, source_ns INTEGER,
//                        writer_guid BLOB, writer_seq INTEGER, codec INTEGER,
//                        raw_size INTEGER, data BLOB,          -- codec 0 raw, 1 zstd
//                        crc32 INTEGER)   -- CRC-32 of the payload (uncompressed), checked on read
//   CREATE INDEX samples_by_time ON samples(receive_ns)
//
// Timestamps are nanoseconds since the Unix epoch (Fast DDS stamps samples with the system
// clock). Any SQLite client can read the file; `sqlite3 FILE 'select ...'` works.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "common/record/recording_backend.hpp"

struct sqlite3;
struct sqlite3_stmt;

namespace teleop::record {

class SqliteWriter : public WriterBackend {
 public:
  /// Creates `path` (the caller removed any old file). @throws RecordingError.
  explicit SqliteWriter(const std::string& path);
  ~SqliteWriter() override;

  int add_topic(const std::string& name, const std::string& type_name, const std::string& qos,
                const std::string& schema) override;
  void set_meta(const std::string& key, const std::string& value) override;
  /// Appends samples in one transaction.
  void append(const std::vector<RecordedSample>& samples) override;
  std::uint64_t raw_bytes() const override { return raw_bytes_; }
  std::uint64_t stored_bytes() const override { return stored_bytes_; }
  std::uint64_t samples_in_file() const override { return committed_; }
  void close() override;

 private:
  void exec(const std::string& sql);
  sqlite3* db_ = nullptr;
  sqlite3_stmt* insert_ = nullptr;
  std::vector<std::uint8_t> zbuf_;
  std::uint64_t raw_bytes_ = 0;
  std::uint64_t stored_bytes_ = 0;
  std::uint64_t committed_ = 0;
};

class SqliteReader : public ReaderBackend {
 public:
  /// Opens `path` read-only. @throws RecordingError if it is not a teleop SQLite recording,
  /// config::ConfigError if its times are out of range.
  explicit SqliteReader(const std::string& path);
  ~SqliteReader() override;

  const std::vector<TopicRecord>& topics() const override { return topics_; }
  std::map<std::string, std::string> meta() const override;
  std::map<int, std::int64_t> counts() const override;
  std::int64_t first_ns() const override { return first_ns_; }
  std::int64_t last_ns() const override { return last_ns_; }
  RecordingHealth health() const override;
  std::string verify_file() override;
  void scan(std::int64_t from_ns, std::int64_t to_ns, const std::vector<int>& topic_ids) override;
  bool next(RecordedSample& out) override;

 private:
  /// The current scan row's CRC against `s`'s payload. @throws config::ConfigError on a mismatch.
  void check_crc(const RecordedSample& s) const;

  std::string path_;
  sqlite3* db_ = nullptr;
  sqlite3_stmt* scan_ = nullptr;
  bool has_crc_ = false;  ///< the samples table has the crc32 column
  std::vector<TopicRecord> topics_;
  std::int64_t first_ns_ = 0, last_ns_ = 0;
};

}  // namespace teleop::record
