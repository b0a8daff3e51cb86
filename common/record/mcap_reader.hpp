#pragma once
// An MCAP reader for files written by mcap_writer.hpp and by other writers that put their
// messages in chunks (zstd or uncompressed). The file is untrusted input: every length, offset,
// opcode and CRC is checked before it is used, and anything out of range is a
// config::ConfigError naming the file, the record and its byte offset, the field, the value and
// what is allowed. Nothing in a file makes the reader read out of bounds, allocate more than
// kMaxChunkBytes for a chunk, or loop forever.
//
// Opening reads the Footer and the summary (Schema, Channel, Chunk Index, Statistics, Metadata
// Index records; the summary CRC is checked) and nothing else: scan() then reads only the
// chunks whose time range overlaps the request (seeking through the Chunk Index). A file
// without a usable footer or summary (a recorder killed with -9, a cut copy) is recovered
// instead: its data section is read from the start, every complete chunk whose CRC checks is
// kept, and health() says what was dropped (a chunk cut by the end of the file, a chunk whose
// CRC fails, the bytes after the last whole record).
//
// scan()/next() return messages in log-time order across chunks, even when chunks overlap in
// time (a k-way merge over the chunks that are open); ties keep file order. Messages written
// outside chunks are counted in health().skipped_messages and not returned.
#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace teleop::record::mcap {

using KeyValues = std::vector<std::pair<std::string, std::string>>;

struct SchemaInfo {
  std::uint16_t id = 0;
  std::string name, encoding, data;
};

struct ChannelInfo {
  std::uint16_t id = 0, schema_id = 0;
  std::string topic, message_encoding;
  KeyValues metadata;
};

struct MetadataInfo {
  std::string name;
  KeyValues entries;
};

struct ChunkInfo {
  std::uint64_t start_ns = 0, end_ns = 0;  ///< log times of its first and last message
  std::uint64_t offset = 0, length = 0;    ///< the Chunk record in the file [bytes]
  std::vector<std::uint16_t> channels;     ///< channels with messages in it (empty: unknown)
};

/// How the file was read and what could not be.
struct Health {
  bool indexed = false;                ///< read through its summary (footer, chunk index)
  bool recovered = false;              ///< no usable summary: the data section was scanned instead
  std::string note;                    ///< why it was scanned and the first problem met
  std::uint64_t dropped_bytes = 0;     ///< bytes not read: a cut record at the end, bad chunks
  std::uint64_t dropped_chunks = 0;    ///< chunks cut by the end of the file or failing CRC
  std::uint64_t dropped_messages = 0;  ///< messages seen in the decodable part of those chunks
  std::uint64_t skipped_messages = 0;  ///< messages outside chunks (not read)
};

/// One message; `data` and `writer_guid` stay valid until the next call of next() or scan().
struct MessageView {
  std::uint16_t channel_id = 0;
  std::uint32_t sequence = 0;
  std::uint64_t log_time_ns = 0, publish_time_ns = 0;
  const std::uint8_t* writer_guid = nullptr;  ///< 16 bytes (kOpWriter), or null
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
};

class Reader {
 public:
  /// Opens `path`. @throws RecordingError when it cannot be read, config::ConfigError when it
  /// is not an MCAP file or is damaged beyond recovery.
  explicit Reader(const std::string& path);
  /// Reads `size` bytes in memory (kept by the caller); `name` is used in messages.
  Reader(const std::uint8_t* data, std::size_t size, const std::string& name);
  ~Reader();
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  const std::map<std::uint16_t, SchemaInfo>& schemas() const { return schemas_; }
  const std::map<std::uint16_t, ChannelInfo>& channels() const { return channels_; }
  /// Metadata records in file order.
  const std::vector<MetadataInfo>& metadata() const { return metadata_; }
  const std::vector<ChunkInfo>& chunks() const { return chunks_; }
  /// Messages per channel (the Statistics record, or counted by reading every chunk).
  const std::map<std::uint16_t, std::uint64_t>& channel_counts();
  /// Log times of the first and last message; both 0 without messages.
  std::uint64_t start_ns() const { return start_ns_; }
  std::uint64_t end_ns() const { return end_ns_; }
  const Health& health() const { return health_; }
  /// Reads the whole data section and checks it against the Data End record's CRC. Returns
  /// "ok" or why it could not be checked ("not recorded" for a CRC of 0, "no Data End record").
  /// @throws config::ConfigError when the CRC does not match.
  std::string verify_data_crc();

  /// Starts a scan of the messages with log time >= from_ns (and < to_ns when to_ns > 0) on
  /// the given channels (empty: all), in log-time order.
  void scan(std::uint64_t from_ns, std::uint64_t to_ns, const std::vector<std::uint16_t>& channels);
  /// The next message of the scan; false at its end. @throws config::ConfigError for a chunk
  /// that is damaged (CRC, sizes, records).
  bool next(MessageView& out);
  /// Chunks read by scans so far (a scan reads only the chunks that overlap its window).
  std::uint64_t chunks_loaded() const { return chunks_loaded_; }

 private:
  struct Source;
  struct Loaded;
  struct ChunkHeader;
  void open();
  bool read_summary();
  void read_summary_records(const std::vector<std::uint8_t>& bytes, std::uint64_t at,
                            std::uint64_t end, std::uint64_t data_end);
  void recover();
  void recover_chunk(std::uint64_t pos, std::uint64_t length, std::vector<std::uint8_t>& records);
  void count_cut_chunk(std::uint64_t pos);
  void read_chunk(std::uint64_t offset, std::uint64_t length, std::vector<std::uint8_t>& records,
                  ChunkHeader& header);
  template <class OnMessage>
  void parse_chunk_records(const std::vector<std::uint8_t>& records, std::uint64_t chunk_offset,
                           bool learn_channels, OnMessage&& on_message);
  void load(std::size_t chunk);
  void finish_open();

  std::string name_;
  std::unique_ptr<Source> source_;
  std::uint64_t size_ = 0, header_end_ = 0, summary_start_ = 0;
  std::map<std::uint16_t, SchemaInfo> schemas_;
  std::map<std::uint16_t, ChannelInfo> channels_;
  std::vector<MetadataInfo> metadata_;
  std::vector<ChunkInfo> chunks_;
  std::map<std::uint16_t, std::uint64_t> counts_;
  bool counts_known_ = false;
  std::uint64_t start_ns_ = 0, end_ns_ = 0;
  Health health_;
  std::string data_crc_status_;
  struct FreeDctx {
    void operator()(void* dctx) const;
  };
  std::unique_ptr<void, FreeDctx> dctx_;  // ZSTD_DCtx, freed even when a constructor throws
  // the scan
  std::vector<std::size_t> candidates_;
  std::size_t next_candidate_ = 0;
  std::uint64_t scan_from_ = 0, scan_to_ = 0;
  std::vector<bool> wanted_;  // by channel id; empty: all
  std::vector<Loaded*> heap_;
  std::vector<std::unique_ptr<Loaded>> pool_;  // owns every loaded chunk
  std::vector<Loaded*> free_;
  Loaded* retired_ = nullptr;
  std::uint64_t load_order_ = 0, chunks_loaded_ = 0;
  std::vector<std::uint8_t> compressed_;
};

}  // namespace teleop::record::mcap
