#pragma once
// An MCAP writer (common/record/mcap_format.hpp; https://mcap.dev/spec), written for a recorder
// that may be killed at any moment or run out of disk:
//
//   magic, Header, [Schema, Channel, Metadata records and Chunks, each chunk followed by one
//   Message Index record per channel in it], Data End (CRC of the data section), summary
//   (Schema, Channel, Chunk Index, Metadata Index and Statistics records, grouped by opcode),
//   Summary Offset records, Footer (CRC of the summary), magic.
//
// Messages go into an in-memory chunk, compressed with zstd and written whole when it holds
// `chunk_bytes` uncompressed bytes or its first message is `chunk_ns` old (tick() checks the
// age), so the file on disk always ends with complete records except for at most the chunk
// being written. A killed writer loses the open chunk (at most chunk_ns of messages, or
// chunk_bytes); every chunk written before it is recovered by mcap_reader.hpp.
//
// A write that fails (a full disk, a file size limit) throws RecordingError, but first the
// writer finishes the file: it cuts the file back to the end of the last whole record, writes
// Data End, the summary and the footer, and when even those do not fit it drops the newest
// chunks one by one until they do. The file is then a valid MCAP file holding every chunk it
// kept (messages_in_file()). Later calls do nothing (close()) or throw (add_*).
//
// Not thread-safe. Steady work (add_message) does not allocate once the chunk buffers have
// grown to their working size.
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace teleop::record::mcap {

class ByteWriter;  // common/record/mcap_format.hpp

struct WriterOptions {
  std::uint64_t chunk_bytes = std::uint64_t{1} << 20;  ///< close a chunk at this size [bytes]
  std::int64_t chunk_ns = 1'000'000'000;  ///< ... or when its first message is this old [ns]
  int zstd_level = 1;                     ///< zstd level of the chunks (1: fastest)
  std::string profile;                    ///< the Header's profile ("": none)
  std::string library = "teleop";         ///< the Header's library
};

using KeyValues = std::vector<std::pair<std::string, std::string>>;

class Writer {
 public:
  /// Creates (or truncates) `path` and writes the magic and the Header.
  /// @throws RecordingError when it cannot.
  Writer(const std::string& path, const WriterOptions& options);
  ~Writer();
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  /// Writes a Schema record; returns its id (1, 2, ...). @throws RecordingError.
  std::uint16_t add_schema(std::string_view name, std::string_view encoding, std::string_view data);
  /// Writes a Channel record; returns its id (1, 2, ...). schema_id 0: no schema.
  std::uint16_t add_channel(std::uint16_t schema_id, std::string_view topic,
                            std::string_view message_encoding, const KeyValues& metadata);
  /// Writes a Metadata record into the data section.
  void add_metadata(std::string_view name, const KeyValues& entries);
  /// Adds a Message to the open chunk; `writer_guid` (16 bytes, may be null) names its DDS
  /// writer. Writes the chunk when it is full or old enough.
  void add_message(std::uint16_t channel_id, std::uint32_t sequence, std::uint64_t log_time_ns,
                   std::uint64_t publish_time_ns, const std::uint8_t* data, std::size_t size,
                   const std::uint8_t* writer_guid);
  /// Writes the open chunk if its first message is chunk_ns old.
  void tick();
  /// Writes the open chunk now (if it holds any message).
  void flush();
  /// Writes the open chunk, Data End, the summary, the footer and the closing magic, then
  /// closes the file. Idempotent; after a failure it only closes.
  void close();

  /// Messages in chunks written to the file (after a failure: in the chunks the file kept).
  std::uint64_t messages_in_file() const { return messages_in_file_; }
  /// Message bytes given to add_message (uncompressed payloads).
  std::uint64_t message_bytes() const { return message_bytes_; }
  /// Bytes written to the file so far.
  std::uint64_t file_bytes() const { return offset_; }
  std::uint64_t chunks_in_file() const;
  bool failed() const { return failed_; }
  /// What failed and how the file was finished; empty while nothing failed.
  const std::string& error() const { return error_; }

 private:
  struct ChunkEntry;
  struct Boundary;
  struct ChannelSlot;
  void write_bytes(const void* data, std::size_t size);
  void write_data_record(std::uint8_t kind);
  void write_chunk();
  void write_tail();
  std::vector<std::uint8_t> build_tail() const;
  void put_chunk_indexes(ByteWriter& w) const;
  void put_metadata_indexes(ByteWriter& w) const;
  void put_statistics(ByteWriter& w) const;
  void mark_boundary(std::uint8_t kind);
  [[noreturn]] void fail(const std::string& what);
  void finish_after_failure();
  ChannelSlot& slot(std::uint16_t channel_id);

  std::string path_;
  WriterOptions options_;
  int fd_ = -1;
  std::uint64_t offset_ = 0;
  std::uint32_t data_crc_ = 0;
  void* cctx_ = nullptr;  // ZSTD_CCtx
  // records of the summary (schemas, channels as written) and the index of the data section
  std::vector<std::vector<std::uint8_t>> schema_records_, channel_records_;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> metadata_at_;  // offset, length
  std::vector<std::string> metadata_names_;
  std::vector<ChunkEntry> chunks_;
  std::vector<Boundary> boundaries_;
  std::vector<ChannelSlot> slots_;  // by channel id - 1
  // the open chunk
  std::vector<std::uint8_t> chunk_, zbuf_, scratch_, index_;
  std::uint64_t chunk_start_ns_ = 0, chunk_end_ns_ = 0;
  std::int64_t chunk_opened_ns_ = 0;  // steady clock
  std::uint64_t chunk_messages_ = 0;
  std::uint64_t messages_in_file_ = 0, message_bytes_ = 0;
  bool failed_ = false, closed_ = false;
  std::string error_;
};

}  // namespace teleop::record::mcap
