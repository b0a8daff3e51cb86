#include "common/record/mcap_reader.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstring>

#include "common/config/config.hpp"
#include "common/record/crc32.hpp"
#include "common/record/mcap_format.hpp"
#include "common/record/recording.hpp"

namespace teleop::record::mcap {

namespace {

constexpr std::uint64_t kNoChunk = ~std::uint64_t{0};
/// A chunk's compressed records may be a little larger than the uncompressed ones.
constexpr std::uint64_t kMaxChunkRecord = kMaxChunkBytes + (std::uint64_t{1} << 20);

/// Where a field was read: the record and its byte offset (in the file, or in the
/// decompressed records of the chunk at byte `chunk`).
struct Where {
  const char* record = "";
  std::uint64_t offset = 0;
  std::uint64_t chunk = kNoChunk;
};

std::string hex32(std::uint32_t v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%08" PRIx32, v);
  return buf;
}

[[noreturn]] void bad(const std::string& name, const Where& w, const std::string& field,
                      const std::string& value, const std::string& allowed) {
  std::string at = "MCAP " + std::string(w.record) + " record at byte " + std::to_string(w.offset);
  if (w.chunk != kNoChunk) {
    at += " of the records of the chunk at byte " + std::to_string(w.chunk);
  }
  throw config::ConfigError(name + ": " + at + ": field '" + field + "': " + value +
                            "; allowed: " + allowed);
}

/// Bounds-checked little-endian reads of one record's content.
class Cursor {
 public:
  Cursor(const std::string& name, Where where, const std::uint8_t* p, std::uint64_t n)
      : name_(name), where_(where), p_(p), n_(n) {}
  std::uint8_t u8(const char* f) { return static_cast<std::uint8_t>(fixed(f, 1)); }
  std::uint16_t u16(const char* f) { return static_cast<std::uint16_t>(fixed(f, 2)); }
  std::uint32_t u32(const char* f) { return static_cast<std::uint32_t>(fixed(f, 4)); }
  std::uint64_t u64(const char* f) { return fixed(f, 8); }
  /// A uint32 length-prefixed string (or byte string).
  std::string str(const char* f) {
    const std::uint64_t n = u32(f);
    need(f, n);
    std::string s(reinterpret_cast<const char*>(p_ + pos_), static_cast<std::size_t>(n));
    pos_ += n;
    return s;
  }
  /// `n` raw bytes.
  const std::uint8_t* bytes(const char* f, std::uint64_t n) {
    need(f, n);
    const std::uint8_t* at = p_ + pos_;
    pos_ += n;
    return at;
  }
  /// A uint32 byte length; the group's end (checked to lie within the record).
  std::uint64_t group_end(const char* f) {
    const std::uint64_t n = u32(f);
    need(f, n);
    return pos_ + n;
  }
  KeyValues string_map(const char* f) {
    KeyValues kv;
    const std::uint64_t end = group_end(f);
    while (pos_ < end) {
      std::string k = str(f);
      std::string v = str(f);
      if (pos_ > end) fail(f, "a map entry runs past the map's length", "entries within it");
      kv.emplace_back(std::move(k), std::move(v));
    }
    return kv;
  }
  std::uint64_t pos() const { return pos_; }
  std::uint64_t left() const { return n_ - pos_; }
  [[noreturn]] void fail(const std::string& field, const std::string& value,
                         const std::string& allowed) const {
    bad(name_, where_, field, value, allowed);
  }

 private:
  void need(const char* f, std::uint64_t n) {
    if (n > left()) {
      fail(f, "needs " + std::to_string(n) + " bytes",
           "at most the " + std::to_string(left()) + " bytes left in the record");
    }
  }
  std::uint64_t fixed(const char* f, unsigned n) {
    need(f, n);
    std::uint64_t v = 0;
    std::memcpy(&v, p_ + pos_, n);  // little-endian host (crc32.cpp asserts it)
    pos_ += n;
    return v;
  }
  const std::string& name_;
  Where where_;
  const std::uint8_t* p_;
  std::uint64_t n_;
  std::uint64_t pos_ = 0;
};

std::uint64_t le64(const std::uint8_t* p) {
  std::uint64_t v = 0;
  std::memcpy(&v, p, 8);
  return v;
}

std::uint32_t le32(const std::uint8_t* p) {
  std::uint32_t v = 0;
  std::memcpy(&v, p, 4);
  return v;
}

SchemaInfo parse_schema(Cursor& c) {
  SchemaInfo s;
  s.id = c.u16("id");
  s.name = c.str("name");
  s.encoding = c.str("encoding");
  s.data = c.str("data");
  return s;
}

ChannelInfo parse_channel(Cursor& c) {
  ChannelInfo ch;
  ch.id = c.u16("id");
  ch.schema_id = c.u16("schema_id");
  ch.topic = c.str("topic");
  ch.message_encoding = c.str("message_encoding");
  ch.metadata = c.string_map("metadata");
  return ch;
}

void check_compression(Cursor& c, const std::string& compression) {
  if (compression != "zstd" && !compression.empty()) {
    c.fail("compression", "'" + compression + "'", "'zstd' or '' (none)");
  }
}

/// A Chunk Index record: the chunk within the data section [header_end, data_end) and at
/// most kMaxChunkRecord bytes long, its time range ordered.
ChunkInfo parse_chunk_index(Cursor& c, std::uint64_t header_end, std::uint64_t data_end) {
  ChunkInfo ci;
  ci.start_ns = c.u64("message_start_time");
  ci.end_ns = c.u64("message_end_time");
  ci.offset = c.u64("chunk_start_offset");
  ci.length = c.u64("chunk_length");
  const std::uint64_t map_end = c.group_end("message_index_offsets");
  while (c.pos() < map_end) {
    ci.channels.push_back(c.u16("message_index_offsets"));
    c.u64("message_index_offsets");
  }
  c.u64("message_index_length");
  check_compression(c, c.str("compression"));
  if (ci.offset < header_end || ci.length < kRecordPrefix || ci.offset > data_end ||
      ci.length > data_end - ci.offset || ci.length > kMaxChunkRecord) {
    c.fail("chunk_start_offset",
           std::to_string(ci.offset) + " (length " + std::to_string(ci.length) + ")",
           "a chunk of at most " + std::to_string(kMaxChunkRecord) + " bytes within the " +
               "data section [" + std::to_string(header_end) + ", " + std::to_string(data_end) +
               ")");
  }
  if (ci.start_ns > ci.end_ns) {
    c.fail("message_start_time", std::to_string(ci.start_ns),
           "at most message_end_time " + std::to_string(ci.end_ns));
  }
  return ci;
}

/// A Statistics record: the per-channel message counts into `counts`, the rest skipped.
void parse_statistics(Cursor& c, std::map<std::uint16_t, std::uint64_t>& counts) {
  c.u64("message_count");
  c.u16("schema_count");
  c.u32("channel_count");
  c.u32("attachment_count");
  c.u32("metadata_count");
  c.u32("chunk_count");
  c.u64("message_start_time");
  c.u64("message_end_time");
  const std::uint64_t map_end = c.group_end("channel_message_counts");
  while (c.pos() < map_end) {
    const std::uint16_t id = c.u16("channel_message_counts");
    counts[id] = c.u64("channel_message_counts");
  }
}

}  // namespace

/// Where the bytes come from: a file (pread) or memory.
struct Reader::Source {
  int fd = -1;
  const std::uint8_t* memory = nullptr;
  std::uint64_t size = 0;
  std::string name;
  ~Source() {
    if (fd >= 0) ::close(fd);
  }
  /// Reads [offset, offset + n); the caller has checked the range against `size`.
  void read(std::uint64_t offset, std::uint64_t n, std::uint8_t* out) const {
    if (offset > size || n > size - offset) {
      throw config::ConfigError(name + ": a read of " + std::to_string(n) + " bytes at byte " +
                                std::to_string(offset) + " runs past the end of the file (" +
                                std::to_string(size) + " bytes)");
    }
    if (n == 0) return;
    if (memory) {
      std::memcpy(out, memory + offset, static_cast<std::size_t>(n));
      return;
    }
    while (n > 0) {
      const ssize_t got = ::pread(fd, out, static_cast<std::size_t>(n), static_cast<off_t>(offset));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) {
        throw RecordingError(name + ": cannot read at byte " + std::to_string(offset) + ": " +
                             (got < 0 ? std::strerror(errno) : "the file shrank"));
      }
      out += got;
      offset += static_cast<std::uint64_t>(got);
      n -= static_cast<std::uint64_t>(got);
    }
  }
};

struct Reader::ChunkHeader {
  std::uint64_t start_ns = 0, end_ns = 0, uncompressed_size = 0;
  std::uint32_t crc = 0;
  std::string compression;
};

struct Reader::Loaded {
  struct Ref {
    std::uint64_t log_ns, publish_ns;
    std::uint32_t sequence;
    std::uint16_t channel;
    bool has_writer;
    std::uint64_t data_at, size;
    std::array<std::uint8_t, 16> writer;
  };
  std::vector<std::uint8_t> data;  // the chunk's decompressed records
  std::vector<Ref> msgs;
  std::size_t next = 0;
  std::uint64_t order = 0;
};

Reader::Reader(const std::string& path) : name_(path), source_(std::make_unique<Source>()) {
  source_->name = path;
  source_->fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (source_->fd < 0) {
    throw RecordingError("cannot open recording '" + path + "': " + std::strerror(errno));
  }
  struct stat st {};
  if (::fstat(source_->fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    throw config::ConfigError(path + ": recording is not a regular file");
  }
  source_->size = static_cast<std::uint64_t>(st.st_size);
  open();
}

Reader::Reader(const std::uint8_t* data, std::size_t size, const std::string& name)
    : name_(name), source_(std::make_unique<Source>()) {
  source_->name = name;
  source_->memory = data;
  source_->size = size;
  open();
}

Reader::~Reader() = default;

void Reader::FreeDctx::operator()(void* dctx) const {
  ZSTD_freeDCtx(static_cast<ZSTD_DCtx*>(dctx));
}

void Reader::open() {
  size_ = source_->size;
  dctx_.reset(ZSTD_createDCtx());
  if (!dctx_) throw RecordingError(name_ + ": out of memory (zstd)");
  std::uint8_t head[8 + 9] = {};
  if (size_ < sizeof head) {
    throw config::ConfigError(name_ + ": " + std::to_string(size_) +
                              " bytes are too few for an MCAP file (magic and Header record)");
  }
  source_->read(0, sizeof head, head);
  if (std::memcmp(head, kMagic, sizeof kMagic) != 0) {
    throw config::ConfigError(name_ + ": not an MCAP file (it does not start with the MCAP magic)");
  }
  const std::uint64_t len = le64(head + 9);
  if (head[8] != kOpHeader || len > kMaxRecordBytes || len > size_ - sizeof head) {
    bad(name_, {"Header", 8}, head[8] != kOpHeader ? "opcode" : "length",
        head[8] != kOpHeader ? std::to_string(head[8]) : std::to_string(len),
        head[8] != kOpHeader ? "1 (Header) right after the magic"
                             : "within the file (" + std::to_string(size_) + " bytes)");
  }
  std::vector<std::uint8_t> header(static_cast<std::size_t>(len));
  source_->read(sizeof head, len, header.data());
  Cursor c(name_, {"Header", 8}, header.data(), len);
  c.str("profile");
  c.str("library");
  header_end_ = sizeof head + len;
  if (!read_summary()) recover();
  finish_open();
}

bool Reader::read_summary() {
  constexpr std::uint64_t kTail = kRecordPrefix + kFooterContent + 8;
  if (size_ < header_end_ + kTail) {
    health_.note = "the file ends without a footer";
    return false;
  }
  std::uint8_t tail[kTail];
  source_->read(size_ - kTail, kTail, tail);
  const std::uint64_t footer_at = size_ - kTail;
  if (std::memcmp(tail + kTail - 8, kMagic, 8) != 0 || tail[0] != kOpFooter ||
      le64(tail + 1) != kFooterContent) {
    health_.note = "the file ends without a footer (the recorder did not finish it)";
    return false;
  }
  const std::uint64_t ss = le64(tail + 9), sos = le64(tail + 17);
  const std::uint32_t crc = le32(tail + 25);
  if (ss == 0) {
    health_.note = "the file has no summary section";
    return false;
  }
  if (ss < header_end_ || ss > footer_at || (sos != 0 && (sos < ss || sos > footer_at)) ||
      footer_at - ss > kMaxSummaryBytes) {
    health_.note = "the footer's summary offsets (" + std::to_string(ss) + ", " +
                   std::to_string(sos) + ") are outside the file's summary area";
    return false;
  }
  // the summary, the summary offsets and the footer up to its CRC
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(footer_at - ss + kRecordPrefix + 16));
  source_->read(ss, bytes.size(), bytes.data());
  if (crc != 0 && crc32(bytes.data(), bytes.size()) != crc) {
    health_.note = "the summary's CRC does not match (" + hex32(crc) + " recorded, " +
                   hex32(crc32(bytes.data(), bytes.size())) + " computed)";
    return false;
  }
  try {
    read_summary_records(bytes, ss, sos != 0 ? sos : footer_at, ss);
  } catch (const config::ConfigError& e) {
    health_.note = std::string("the summary is damaged: ") + e.what();
    schemas_.clear();
    channels_.clear();
    metadata_.clear();
    chunks_.clear();
    counts_.clear();
    counts_known_ = false;
    return false;
  }
  std::uint64_t messages = 0;
  for (const auto& [id, n] : counts_) messages += n;
  if (chunks_.empty() && (messages > 0 || !counts_known_)) {
    health_.note = "the summary has no chunk index";
    chunks_.clear();
    return false;
  }
  summary_start_ = ss;
  health_.indexed = true;
  return true;
}

void Reader::read_summary_records(const std::vector<std::uint8_t>& bytes, std::uint64_t at,
                                  std::uint64_t end, std::uint64_t data_end) {
  const std::uint64_t base = at;
  while (at < end) {
    const std::uint64_t i = at - base;
    if (end - at < kRecordPrefix) bad(name_, {"summary", at}, "length", "cut", "9 bytes or more");
    const std::uint8_t op = bytes[i];
    const std::uint64_t len = le64(bytes.data() + i + 1);
    if (len > end - at - kRecordPrefix) {
      bad(name_, {"summary", at}, "length", std::to_string(len),
          "within the summary (" + std::to_string(end - at - kRecordPrefix) + " bytes left)");
    }
    const std::uint8_t* p = bytes.data() + i + kRecordPrefix;
    if (op == kOpSchema) {
      Cursor c(name_, {"Schema", at}, p, len);
      SchemaInfo s = parse_schema(c);
      if (s.id != 0) schemas_.emplace(s.id, std::move(s));
    } else if (op == kOpChannel) {
      Cursor c(name_, {"Channel", at}, p, len);
      ChannelInfo ch = parse_channel(c);
      channels_.emplace(ch.id, std::move(ch));
    } else if (op == kOpChunkIndex) {
      Cursor c(name_, {"Chunk Index", at}, p, len);
      ChunkInfo ci = parse_chunk_index(c, header_end_, data_end);
      chunks_.push_back(std::move(ci));
    } else if (op == kOpStatistics) {
      Cursor c(name_, {"Statistics", at}, p, len);
      parse_statistics(c, counts_);
      counts_known_ = true;
    } else if (op == kOpMetadataIndex) {
      Cursor c(name_, {"Metadata Index", at}, p, len);
      const std::uint64_t off = c.u64("offset"), n = c.u64("length");
      if (off < header_end_ || n < kRecordPrefix || n > kMaxRecordBytes || off > data_end ||
          n > data_end - off) {
        c.fail("offset", std::to_string(off) + " (length " + std::to_string(n) + ")",
               "a record within the data section [" + std::to_string(header_end_) + ", " +
                   std::to_string(data_end) + ")");
      }
      std::vector<std::uint8_t> rec(static_cast<std::size_t>(n));
      source_->read(off, n, rec.data());
      if (rec[0] != kOpMetadata || le64(rec.data() + 1) != n - kRecordPrefix) {
        c.fail("offset", std::to_string(off), "the offset of a Metadata record of that length");
      }
      Cursor m(name_, {"Metadata", off}, rec.data() + kRecordPrefix, n - kRecordPrefix);
      MetadataInfo info;
      info.name = m.str("name");
      info.entries = m.string_map("metadata");
      metadata_.push_back(std::move(info));
    }
    at += kRecordPrefix + len;
  }
  for (const ChunkInfo& ci : chunks_) {
    for (std::uint16_t id : ci.channels) {
      if (!channels_.count(id)) {
        bad(name_, {"Chunk Index", ci.offset}, "message_index_offsets",
            "channel " + std::to_string(id), "channels with a Channel record in the summary");
      }
    }
  }
}

void Reader::read_chunk(std::uint64_t offset, std::uint64_t length,
                        std::vector<std::uint8_t>& records, ChunkHeader& h) {
  const Where where{"Chunk", offset};
  if (length < kRecordPrefix || length > kMaxChunkRecord || offset > size_ ||
      length > size_ - offset) {
    bad(name_, where, "length", std::to_string(length),
        "at most " + std::to_string(kMaxChunkRecord) + " bytes, within the file");
  }
  compressed_.resize(static_cast<std::size_t>(length));
  source_->read(offset, length, compressed_.data());
  if (compressed_[0] != kOpChunk || le64(compressed_.data() + 1) != length - kRecordPrefix) {
    bad(name_, where, "opcode", std::to_string(compressed_[0]),
        "6 (Chunk) with the length its index gives");
  }
  Cursor c(name_, where, compressed_.data() + kRecordPrefix, length - kRecordPrefix);
  h.start_ns = c.u64("message_start_time");
  h.end_ns = c.u64("message_end_time");
  h.uncompressed_size = c.u64("uncompressed_size");
  h.crc = c.u32("uncompressed_crc");
  h.compression = c.str("compression");
  check_compression(c, h.compression);
  const std::uint64_t n = c.u64("records");
  const std::uint8_t* in = c.bytes("records", n);
  if (h.uncompressed_size > kMaxChunkBytes || (h.compression.empty() && n != h.uncompressed_size)) {
    c.fail(
        "uncompressed_size", std::to_string(h.uncompressed_size),
        "at most " + std::to_string(kMaxChunkBytes) + ", and the records' size when uncompressed");
  }
  records.resize(static_cast<std::size_t>(h.uncompressed_size));
  if (h.compression.empty()) {
    if (n > 0) std::memcpy(records.data(), in, static_cast<std::size_t>(n));
  } else {
    const std::size_t got =
        ZSTD_decompressDCtx(static_cast<ZSTD_DCtx*>(dctx_.get()), records.data(), records.size(),
                            in, static_cast<std::size_t>(n));
    if (ZSTD_isError(got) || got != records.size()) {
      c.fail("records",
             ZSTD_isError(got) ? std::string("do not decompress (") + ZSTD_getErrorName(got) + ")"
                               : "decompress to " + std::to_string(got) + " bytes",
             "zstd data of uncompressed_size " + std::to_string(h.uncompressed_size) + " bytes");
    }
  }
  if (h.crc != 0) {
    const std::uint32_t got = crc32(records.data(), records.size());
    if (got != h.crc) {
      c.fail("uncompressed_crc", hex32(h.crc),
             "the CRC-32 of the decompressed records, " + hex32(got));
    }
  }
  if (h.start_ns > h.end_ns) {
    c.fail("message_start_time", std::to_string(h.start_ns),
           "at most message_end_time " + std::to_string(h.end_ns));
  }
}

template <class OnMessage>
void Reader::parse_chunk_records(const std::vector<std::uint8_t>& records,
                                 std::uint64_t chunk_offset, bool learn_channels,
                                 OnMessage&& on_message) {
  std::vector<std::pair<std::uint16_t, const std::uint8_t*>> writers;
  const std::uint64_t n = records.size();
  std::uint64_t pos = 0;
  while (pos < n) {
    const Where where{"", pos, chunk_offset};
    if (n - pos < kRecordPrefix) bad(name_, where, "length", "cut", "9 bytes or more");
    const std::uint8_t op = records[pos];
    const std::uint64_t len = le64(records.data() + pos + 1);
    if (len > n - pos - kRecordPrefix) {
      bad(name_, where, "length", std::to_string(len),
          "within the chunk (" + std::to_string(n - pos - kRecordPrefix) + " bytes left)");
    }
    const std::uint8_t* p = records.data() + pos + kRecordPrefix;
    if (op == kOpMessage) {
      Cursor c(name_, {"Message", pos, chunk_offset}, p, len);
      MessageView m;
      m.channel_id = c.u16("channel_id");
      m.sequence = c.u32("sequence");
      m.log_time_ns = c.u64("log_time");
      m.publish_time_ns = c.u64("publish_time");
      m.size = static_cast<std::size_t>(c.left());
      m.data = p + kMessageHeader;
      if (!channels_.count(m.channel_id)) {
        c.fail("channel_id", std::to_string(m.channel_id), "a channel defined before it");
      }
      for (const auto& [id, guid] : writers) {
        if (id == m.channel_id) m.writer_guid = guid;
      }
      on_message(m, pos + kRecordPrefix + kMessageHeader);
    } else if (op == kOpWriter) {
      Cursor c(name_, {"teleop writer (0x80)", pos, chunk_offset}, p, len);
      const std::uint16_t id = c.u16("channel_id");
      const std::uint8_t* guid = c.bytes("writer_guid", 16);
      auto it = std::find_if(writers.begin(), writers.end(),
                             [id](const auto& w) { return w.first == id; });
      if (it == writers.end()) {
        writers.emplace_back(id, guid);
      } else {
        it->second = guid;
      }
    } else if (learn_channels && op == kOpSchema) {
      Cursor c(name_, {"Schema", pos, chunk_offset}, p, len);
      SchemaInfo s = parse_schema(c);
      if (s.id != 0) schemas_.emplace(s.id, std::move(s));
    } else if (learn_channels && op == kOpChannel) {
      Cursor c(name_, {"Channel", pos, chunk_offset}, p, len);
      ChannelInfo ch = parse_channel(c);
      channels_.emplace(ch.id, std::move(ch));
    }
    pos += kRecordPrefix + len;
  }
}

void Reader::recover() {
  health_.recovered = true;
  data_crc_status_ = "not checked (the file was recovered without its summary)";
  std::vector<std::uint8_t> content, records;
  std::uint64_t pos = header_end_;
  while (true) {
    if (pos == size_) {
      health_.note += "; it ends after its last whole record, without a Data End record";
      break;
    }
    std::uint8_t prefix[kRecordPrefix] = {};
    const std::uint64_t left = size_ - pos;
    if (left >= kRecordPrefix) source_->read(pos, kRecordPrefix, prefix);
    const std::uint64_t len = le64(prefix + 1);
    if (left < kRecordPrefix || prefix[0] == 0 || len > left - kRecordPrefix) {
      if (left >= kRecordPrefix && prefix[0] == kOpChunk) {
        ++health_.dropped_chunks;
        count_cut_chunk(pos);
      }
      health_.dropped_bytes += left;
      health_.note += "; the record at byte " + std::to_string(pos) +
                      " is cut by the end of the file: its " + std::to_string(left) +
                      " bytes are dropped";
      break;
    }
    const std::uint8_t op = prefix[0];
    if (op == kOpDataEnd || op == kOpFooter) break;
    if (op == kOpChunk) {
      try {
        recover_chunk(pos, kRecordPrefix + len, records);
      } catch (const config::ConfigError& e) {
        ++health_.dropped_chunks;
        health_.dropped_bytes += kRecordPrefix + len;
        health_.note += std::string("; a chunk is dropped: ") + e.what();
      }
    } else if (op == kOpSchema || op == kOpChannel || op == kOpMetadata || op == kOpMessage) {
      if (len > kMaxRecordBytes) {
        bad(name_, {"data section", pos}, "length", std::to_string(len),
            "at most " + std::to_string(kMaxRecordBytes) + " bytes");
      }
      content.resize(static_cast<std::size_t>(len));
      source_->read(pos + kRecordPrefix, len, content.data());
      Cursor c(name_, {"data section", pos}, content.data(), len);
      if (op == kOpSchema) {
        SchemaInfo s = parse_schema(c);
        if (s.id != 0) schemas_.emplace(s.id, std::move(s));
      } else if (op == kOpChannel) {
        ChannelInfo ch = parse_channel(c);
        channels_.emplace(ch.id, std::move(ch));
      } else if (op == kOpMetadata) {
        MetadataInfo m;
        m.name = c.str("name");
        m.entries = c.string_map("metadata");
        metadata_.push_back(std::move(m));
      } else {
        ++health_.skipped_messages;
      }
    }
    pos += kRecordPrefix + len;
  }
  if (health_.note.rfind("; ", 0) == 0) health_.note.erase(0, 2);
  counts_known_ = true;
}

void Reader::recover_chunk(std::uint64_t pos, std::uint64_t length,
                           std::vector<std::uint8_t>& records) {
  ChunkHeader h;
  read_chunk(pos, length, records, h);
  ChunkInfo ci;
  ci.offset = pos;
  ci.length = length;
  bool any = false;
  std::map<std::uint16_t, std::uint64_t> counts;
  parse_chunk_records(records, pos, true, [&](const MessageView& m, std::uint64_t) {
    ci.start_ns = any ? std::min(ci.start_ns, m.log_time_ns) : m.log_time_ns;
    ci.end_ns = any ? std::max(ci.end_ns, m.log_time_ns) : m.log_time_ns;
    any = true;
    ++counts[m.channel_id];
  });
  if (!any) return;  // nothing to read in it
  if (ci.start_ns < h.start_ns || ci.end_ns > h.end_ns) {
    bad(name_, {"Chunk", pos}, "message_start_time",
        std::to_string(h.start_ns) + " to " + std::to_string(h.end_ns),
        "a range holding its messages' log times, " + std::to_string(ci.start_ns) + " to " +
            std::to_string(ci.end_ns));
  }
  for (const auto& [id, n] : counts) {
    ci.channels.push_back(id);
    counts_[id] += n;
  }
  chunks_.push_back(std::move(ci));
}

void Reader::count_cut_chunk(std::uint64_t pos) {
  // the decodable start of a chunk cut by the end of the file: how many messages are lost
  const std::uint64_t avail = std::min(size_ - pos - kRecordPrefix, kMaxChunkRecord);
  std::vector<std::uint8_t> content(static_cast<std::size_t>(avail));
  source_->read(pos + kRecordPrefix, avail, content.data());
  try {
    Cursor c(name_, {"Chunk", pos}, content.data(), avail);
    c.u64("message_start_time");
    c.u64("message_end_time");
    const std::uint64_t usize = std::min(c.u64("uncompressed_size"), kMaxChunkBytes);
    c.u32("uncompressed_crc");
    const std::string compression = c.str("compression");
    const std::uint64_t declared = c.u64("records");
    const std::uint64_t n = std::min(declared, c.left());
    const std::uint8_t* in = c.bytes("records", n);
    std::vector<std::uint8_t> out(static_cast<std::size_t>(usize));
    std::size_t produced = 0;
    if (compression.empty()) {
      produced = static_cast<std::size_t>(std::min(n, usize));
      if (produced > 0) std::memcpy(out.data(), in, produced);
    } else if (compression == "zstd") {
      auto* d = static_cast<ZSTD_DCtx*>(dctx_.get());
      ZSTD_DCtx_reset(d, ZSTD_reset_session_only);
      ZSTD_inBuffer ib{in, static_cast<std::size_t>(n), 0};
      ZSTD_outBuffer ob{out.data(), out.size(), 0};
      while (ib.pos < ib.size && ob.pos < ob.size) {
        const std::size_t r = ZSTD_decompressStream(d, &ob, &ib);
        if (ZSTD_isError(r) || r == 0) break;
      }
      produced = ob.pos;
    }
    for (std::uint64_t p = 0; produced - p >= kRecordPrefix;) {
      const std::uint64_t len = le64(out.data() + p + 1);
      if (len > produced - p - kRecordPrefix) break;
      if (out[p] == kOpMessage) ++health_.dropped_messages;
      p += kRecordPrefix + len;
    }
  } catch (const config::ConfigError&) {
    // not even the chunk's header survived: nothing to count
  }
}

void Reader::finish_open() {
  std::stable_sort(chunks_.begin(), chunks_.end(), [](const ChunkInfo& a, const ChunkInfo& b) {
    return a.start_ns != b.start_ns ? a.start_ns < b.start_ns : a.offset < b.offset;
  });
  for (std::size_t i = 0; i < chunks_.size(); ++i) {
    start_ns_ = i == 0 ? chunks_[i].start_ns : std::min(start_ns_, chunks_[i].start_ns);
    end_ns_ = i == 0 ? chunks_[i].end_ns : std::max(end_ns_, chunks_[i].end_ns);
  }
}

const std::map<std::uint16_t, std::uint64_t>& Reader::channel_counts() {
  if (!counts_known_) {
    std::vector<std::uint8_t> records;
    for (const ChunkInfo& ci : chunks_) {
      ChunkHeader h;
      read_chunk(ci.offset, ci.length, records, h);
      parse_chunk_records(records, ci.offset, false,
                          [&](const MessageView& m, std::uint64_t) { ++counts_[m.channel_id]; });
    }
    counts_known_ = true;
  }
  return counts_;
}

std::string Reader::verify_data_crc() {
  if (!health_.indexed) return data_crc_status_;
  constexpr std::uint64_t kDataEnd = kRecordPrefix + 4;
  std::uint8_t rec[kDataEnd] = {};
  const std::uint64_t at = summary_start_ - kDataEnd;
  if (summary_start_ < header_end_ + kDataEnd) return "no Data End record";
  source_->read(at, kDataEnd, rec);
  if (rec[0] != kOpDataEnd || le64(rec + 1) != 4) return "no Data End record";
  const std::uint32_t want = le32(rec + kRecordPrefix);
  if (want == 0) return "not recorded";
  std::vector<std::uint8_t> block(std::size_t{1} << 20);
  std::uint32_t crc = 0;
  for (std::uint64_t p = 0; p < at;) {
    const std::uint64_t n = std::min<std::uint64_t>(block.size(), at - p);
    source_->read(p, n, block.data());
    crc = crc32_update(crc, block.data(), static_cast<std::size_t>(n));
    p += n;
  }
  if (crc != want) {
    bad(name_, {"Data End", at}, "data_section_crc", hex32(want),
        "the CRC-32 of the bytes before it, " + hex32(crc));
  }
  return "ok";
}

void Reader::scan(std::uint64_t from_ns, std::uint64_t to_ns,
                  const std::vector<std::uint16_t>& channels) {
  for (Loaded* l : heap_) free_.push_back(l);
  heap_.clear();
  if (retired_) free_.push_back(retired_);
  retired_ = nullptr;
  scan_from_ = from_ns;
  scan_to_ = to_ns;
  wanted_.clear();
  if (!channels.empty()) {
    wanted_.assign(65536, false);
    for (std::uint16_t c : channels) wanted_[c] = true;
  }
  candidates_.clear();
  next_candidate_ = 0;
  for (std::size_t i = 0; i < chunks_.size(); ++i) {
    const ChunkInfo& ci = chunks_[i];
    if (ci.end_ns < from_ns || (to_ns > 0 && ci.start_ns >= to_ns)) continue;
    if (!wanted_.empty() && !ci.channels.empty() &&
        std::none_of(ci.channels.begin(), ci.channels.end(),
                     [this](std::uint16_t c) { return wanted_[c]; })) {
      continue;
    }
    candidates_.push_back(i);
  }
}

namespace {
/// Heap order: the loaded chunk whose next message is earliest (then loaded first) on top.
constexpr auto later = [](const auto* a, const auto* b) {
  const auto ta = a->msgs[a->next].log_ns, tb = b->msgs[b->next].log_ns;
  return ta != tb ? ta > tb : a->order > b->order;
};
}  // namespace

void Reader::load(std::size_t index) {
  const ChunkInfo& ci = chunks_[index];
  Loaded* l = nullptr;
  if (free_.empty()) {
    pool_.push_back(std::make_unique<Loaded>());
    l = pool_.back().get();
  } else {
    l = free_.back();
    free_.pop_back();
  }
  l->msgs.clear();
  l->next = 0;
  l->order = load_order_++;
  ChunkHeader h;
  read_chunk(ci.offset, ci.length, l->data, h);
  ++chunks_loaded_;
  if (health_.indexed && (h.start_ns != ci.start_ns || h.end_ns != ci.end_ns)) {
    bad(name_, {"Chunk", ci.offset}, "message_start_time",
        std::to_string(h.start_ns) + " to " + std::to_string(h.end_ns),
        "the times its Chunk Index gives, " + std::to_string(ci.start_ns) + " to " +
            std::to_string(ci.end_ns));
  }
  parse_chunk_records(l->data, ci.offset, false, [&](const MessageView& m, std::uint64_t at) {
    if (m.log_time_ns < h.start_ns || m.log_time_ns > h.end_ns) {
      bad(name_, {"Message", at, ci.offset}, "log_time", std::to_string(m.log_time_ns),
          "within its chunk's [" + std::to_string(h.start_ns) + ", " + std::to_string(h.end_ns) +
              "]");
    }
    if (m.log_time_ns < scan_from_ || (scan_to_ > 0 && m.log_time_ns >= scan_to_)) return;
    if (!wanted_.empty() && !wanted_[m.channel_id]) return;
    Loaded::Ref r{m.log_time_ns,
                  m.publish_time_ns,
                  m.sequence,
                  m.channel_id,
                  m.writer_guid != nullptr,
                  at,
                  m.size,
                  {}};
    if (m.writer_guid) std::memcpy(r.writer.data(), m.writer_guid, 16);
    l->msgs.push_back(r);
  });
  std::stable_sort(l->msgs.begin(), l->msgs.end(),
                   [](const Loaded::Ref& a, const Loaded::Ref& b) { return a.log_ns < b.log_ns; });
  if (l->msgs.empty()) {
    free_.push_back(l);
    return;
  }
  heap_.push_back(l);
  std::push_heap(heap_.begin(), heap_.end(), later);
}

bool Reader::next(MessageView& out) {
  if (retired_) {
    free_.push_back(retired_);
    retired_ = nullptr;
  }
  // open every chunk that may hold a message earlier than the earliest one open
  while (next_candidate_ < candidates_.size() &&
         (heap_.empty() || chunks_[candidates_[next_candidate_]].start_ns <=
                               heap_.front()->msgs[heap_.front()->next].log_ns)) {
    load(candidates_[next_candidate_++]);
  }
  if (heap_.empty()) return false;
  std::pop_heap(heap_.begin(), heap_.end(), later);
  Loaded* l = heap_.back();
  heap_.pop_back();
  const Loaded::Ref& r = l->msgs[l->next++];
  out.channel_id = r.channel;
  out.sequence = r.sequence;
  out.log_time_ns = r.log_ns;
  out.publish_time_ns = r.publish_ns;
  out.writer_guid = r.has_writer ? r.writer.data() : nullptr;
  out.data = l->data.data() + r.data_at;
  out.size = static_cast<std::size_t>(r.size);
  if (l->next < l->msgs.size()) {
    heap_.push_back(l);
    std::push_heap(heap_.begin(), heap_.end(), later);
  } else {
    retired_ = l;
  }
  return true;
}

}  // namespace teleop::record::mcap
