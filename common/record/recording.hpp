#pragma once
// A recording of a session: every sample's serialized payload (CDR with its encapsulation
// header, byte for byte as its writer sent it), its topic, its source timestamp (the writer's
// clock), its receive timestamp (the recorder's clock), the writer's GUID and sequence number.
// Two file formats, one interface:
//
//  - MCAP (the default; mcap_writer.hpp, mcap_reader.hpp): one Schema per type (encoding
//    `omgidl`, the IDL text of idl/), one Channel per topic (message encoding `cdr`, metadata
//    `qos`), each sample a Message (log_time = receive time, publish_time = source time,
//    sequence = the writer's sequence number, low 32 bits), zstd chunks with message indexes
//    and a summary for seeking. The writer's GUID rides in a small extension record
//    (mcap_format.hpp, kOpWriter). Foxglove, Lichtblick and @mcap/core open it as it is.
//  - SQLite (sqlite_recording.hpp): the project's first format, still written on request and
//    always readable.
//
// The reader tells them apart by their first bytes, never by the file name.
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

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
  std::int64_t writer_seq = 0;        ///< the writer's DDS sequence number (MCAP: low 32 bits)
  std::vector<std::uint8_t> payload;  ///< serialized CDR payload with encapsulation header
};

struct TopicRecord {
  int id = 0;
  std::string name;
  std::string type_name;
  std::string qos;  ///< client/record/topic_table.hpp qos_name()
};

enum class RecordingFormat { kMcap, kSqlite };

/// "mcap" or "sqlite".
const char* format_name(RecordingFormat format);
/// The format a new recording named `path` gets when none is asked for: SQLite for the
/// extensions .db, .sqlite and .sqlite3, MCAP for every other name (.mcap, none, ...).
RecordingFormat format_for_path(const std::string& path);
/// "mcap" or "sqlite". @throws config::ConfigError naming `flag`, the text and the choices.
RecordingFormat parse_format(const std::string& flag, const std::string& text);
/// The format of an existing file from its first bytes (the MCAP magic, SQLite's header), or
/// nothing when it is neither or cannot be read.
std::optional<RecordingFormat> detect_format(const std::string& path);

/// How an MCAP recording is chunked (a killed recorder loses at most its open chunk).
struct McapOptions {
  std::uint64_t chunk_bytes = std::uint64_t{1} << 20;  ///< close a chunk at this size [bytes]
  std::int64_t chunk_ns = 1'000'000'000;  ///< ... or when its first sample is this old [ns]
  int zstd_level = 1;
};

class WriterBackend;
class ReaderBackend;

/// Writes a recording. Not thread-safe: one thread appends.
class RecordingWriter {
 public:
  /// Creates (or replaces) `path` in `format`. @throws config::ConfigError for an empty name
  /// or a path that exists and is not a regular file, RecordingError when it cannot be created.
  RecordingWriter(const std::string& path, RecordingFormat format, const McapOptions& mcap = {});
  /// The same with format_for_path(path).
  explicit RecordingWriter(const std::string& path);
  ~RecordingWriter();
  RecordingWriter(const RecordingWriter&) = delete;
  RecordingWriter& operator=(const RecordingWriter&) = delete;

  RecordingFormat format() const { return format_; }
  /// Declares a topic; returns its id. `schema`: the IDL text of `type_name` for MCAP (empty:
  /// looked up in the IDL the program was built with, idl/idl_text.hpp).
  int add_topic(const std::string& name, const std::string& type_name, const std::string& qos,
                const std::string& schema = "");
  void set_meta(const std::string& key, const std::string& value);
  /// Appends samples (SQLite: one transaction; MCAP: into the open chunk, written when full or
  /// old). An empty batch still lets MCAP write a chunk that has grown old.
  /// @throws RecordingError when the file cannot be written (a full disk): MCAP has by then
  /// closed the file as a valid one holding its complete chunks (samples_in_file()).
  void append(const std::vector<RecordedSample>& samples);
  /// Payload bytes appended / bytes stored in the file so far.
  std::uint64_t raw_bytes() const;
  std::uint64_t stored_bytes() const;
  /// Samples in the file now (MCAP: in complete chunks; SQLite: committed).
  std::uint64_t samples_in_file() const;
  /// Finishes and closes the file (also done by the destructor, which swallows errors).
  /// @throws RecordingError when the file cannot be finished.
  void close();

 private:
  RecordingFormat format_;
  std::unique_ptr<WriterBackend> impl_;
};

/// Largest payload a recorded sample may declare (raw_size) [bytes]; a level-6 mesh frame is
/// under 1 MB.
constexpr std::int64_t kMaxSampleBytes = std::int64_t{64} << 20;
/// Longest span of receive times a recording may have [ns] (30 days).
constexpr std::int64_t kMaxRecordingSpanNs = std::int64_t{30} * 86400 * 1000000000;

/// How a recording was read.
struct RecordingHealth {
  bool recovered = false;  ///< MCAP without a usable summary: its data section was scanned
  std::string how;         ///< "summary and chunk index", "recovered by a scan", "SQLite"
  std::string note;        ///< why it was recovered and what was dropped
  std::uint64_t chunks = 0;
  std::uint64_t dropped_bytes = 0, dropped_chunks = 0, dropped_messages = 0;
  std::uint64_t skipped_messages = 0;  ///< MCAP messages outside chunks (not read)
};

/// Reads a recording of either format. What is read from the file is checked before use: a
/// FIFO or device is refused at open, negative receive times or a span above
/// kMaxRecordingSpanNs at open, a sample's size outside [0, kMaxSampleBytes] when it is read,
/// every MCAP length, offset and CRC (mcap_reader.hpp); each is a config::ConfigError naming
/// the file and the value.
class RecordingReader {
 public:
  /// Opens `path` read-only. @throws RecordingError if it is not a recording (neither MCAP nor
  /// a teleop SQLite file) or cannot be read, config::ConfigError if it is not a regular file,
  /// its times are out of range or it is damaged beyond recovery.
  explicit RecordingReader(const std::string& path);
  ~RecordingReader();
  RecordingReader(const RecordingReader&) = delete;
  RecordingReader& operator=(const RecordingReader&) = delete;

  RecordingFormat format() const { return format_; }
  const std::vector<TopicRecord>& topics() const;
  std::map<std::string, std::string> meta() const;
  /// Samples per topic id.
  std::map<int, std::int64_t> counts() const;
  /// First and last receive time [ns]; both 0 for an empty recording.
  std::int64_t first_ns() const;
  std::int64_t last_ns() const;
  RecordingHealth health() const;
  /// Checks what the format can check over the whole file without decoding samples (MCAP: the
  /// data section's CRC): "ok", or why it could not. @throws config::ConfigError on a mismatch.
  std::string verify_file();

  /// Starts a scan of the samples with receive time >= from_ns (and < to_ns if to_ns > 0), in
  /// receive order, optionally of the given topic ids only (empty: all).
  void scan(std::int64_t from_ns, std::int64_t to_ns = 0, const std::vector<int>& topic_ids = {});
  /// Next sample of the scan; false at the end. @throws config::ConfigError for a sample whose
  /// sizes are out of range or a damaged chunk, RecordingError for one that does not decompress.
  bool next(RecordedSample& out);
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  RecordingFormat format_ = RecordingFormat::kMcap;
  std::unique_ptr<ReaderBackend> impl_;
};

}  // namespace teleop::record
