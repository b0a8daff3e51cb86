#include "common/record/mcap_writer.hpp"

#include <fcntl.h>
#include <unistd.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <map>
#include <stdexcept>

#include "common/record/crc32.hpp"
#include "common/record/mcap_format.hpp"
#include "common/record/recording.hpp"

namespace teleop::record::mcap {

namespace {

/// A failed write(2): caught inside the writer, turned into RecordingError by fail().
struct IoFailure {
  int err = 0;
};

std::int64_t steady_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

enum BoundaryKind : std::uint8_t { kHeader, kSchema, kChannel, kMetadata, kChunk };

void put_map(ByteWriter& w, const KeyValues& kv) {
  const std::size_t at = w.begin_group();
  for (const auto& [k, v] : kv) {
    w.str(k);
    w.str(v);
  }
  w.end_group(at);
}

}  // namespace

struct Writer::ChunkEntry {
  std::uint64_t start_ns = 0, end_ns = 0;
  std::uint64_t offset = 0, length = 0;
  std::vector<std::pair<std::uint16_t, std::uint64_t>> index_offsets;  // channel, offset
  std::vector<std::pair<std::uint16_t, std::uint64_t>> counts;         // channel, messages
  std::uint64_t index_length = 0;
  std::uint64_t compressed = 0, uncompressed = 0;
  std::uint64_t messages = 0;
};

/// The end of a whole record (or a chunk with its message indexes) and the data section's CRC
/// there: where a failed file is cut back to.
struct Writer::Boundary {
  std::uint64_t end = 0;
  std::uint32_t crc = 0;
  std::uint8_t kind = kHeader;
};

struct Writer::ChannelSlot {
  std::vector<std::pair<std::uint64_t, std::uint64_t>> index;  // log time, offset in chunk
  std::uint8_t guid[16] = {};
  bool writer_known = false;  // a kOpWriter record for this channel is in the open chunk
};

Writer::Writer(const std::string& path, const WriterOptions& options)
    : path_(path), options_(options) {
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    throw RecordingError("cannot create recording '" + path + "': " + std::strerror(errno));
  }
  cctx_ = ZSTD_createCCtx();
  if (!cctx_) {
    ::close(fd_);
    throw RecordingError("cannot create recording '" + path + "': out of memory (zstd)");
  }
  const std::uint64_t reserve = std::min<std::uint64_t>(options_.chunk_bytes, 64u << 20);
  chunk_.reserve(reserve + (64u << 10));
  zbuf_.reserve(ZSTD_compressBound(chunk_.capacity()));
  scratch_.reserve(4096);
  std::vector<std::uint8_t> head;
  ByteWriter w(head);
  w.raw(kMagic, sizeof kMagic);
  const std::size_t at = w.begin_record(kOpHeader);
  w.str(options_.profile);
  w.str(options_.library);
  w.end_record(at);
  try {
    write_bytes(head.data(), head.size());
  } catch (const IoFailure& e) {
    ::close(fd_);
    ZSTD_freeCCtx(static_cast<ZSTD_CCtx*>(cctx_));
    throw RecordingError("cannot write recording '" + path + "': " + std::strerror(e.err));
  }
  mark_boundary(kHeader);
}

Writer::~Writer() {
  try {
    close();
  } catch (...) {
  }
  if (fd_ >= 0) ::close(fd_);
  ZSTD_freeCCtx(static_cast<ZSTD_CCtx*>(cctx_));
}

std::uint64_t Writer::chunks_in_file() const { return chunks_.size(); }

void Writer::write_bytes(const void* data, std::size_t size) {
  const auto* p = static_cast<const std::uint8_t*>(data);
  while (size > 0) {
    const ssize_t n = ::pwrite(fd_, p, size, static_cast<off_t>(offset_));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) throw IoFailure{n < 0 ? errno : ENOSPC};
    data_crc_ = crc32_update(data_crc_, p, static_cast<std::size_t>(n));
    offset_ += static_cast<std::uint64_t>(n);
    p += n;
    size -= static_cast<std::size_t>(n);
  }
}

void Writer::mark_boundary(std::uint8_t kind) { boundaries_.push_back({offset_, data_crc_, kind}); }

Writer::ChannelSlot& Writer::slot(std::uint16_t channel_id) {
  if (channel_id == 0 || channel_id > slots_.size()) {
    throw std::invalid_argument("mcap::Writer: channel " + std::to_string(channel_id) +
                                " was not added");
  }
  return slots_[channel_id - 1u];
}

void Writer::fail(const std::string& what) {
  failed_ = true;
  error_ = path_ + ": " + what;
  finish_after_failure();
  throw RecordingError(error_);
}

void Writer::write_data_record(std::uint8_t kind) {
  if (failed_ || closed_) throw RecordingError(path_ + ": the recording is closed");
  try {
    write_bytes(scratch_.data(), scratch_.size());
  } catch (const IoFailure& e) {
    fail(std::strerror(e.err));
  }
  mark_boundary(kind);
}

std::uint16_t Writer::add_schema(std::string_view name, std::string_view encoding,
                                 std::string_view data) {
  if (schema_records_.size() >= 0xFFFF) throw RecordingError(path_ + ": too many schemas");
  const auto id = static_cast<std::uint16_t>(schema_records_.size() + 1);
  scratch_.clear();
  ByteWriter w(scratch_);
  const std::size_t at = w.begin_record(kOpSchema);
  w.u16(id);
  w.str(name);
  w.str(encoding);
  w.str(data);  // uint32 length-prefixed bytes: the same encoding as a string
  w.end_record(at);
  write_data_record(kSchema);
  schema_records_.push_back(scratch_);
  return id;
}

std::uint16_t Writer::add_channel(std::uint16_t schema_id, std::string_view topic,
                                  std::string_view message_encoding, const KeyValues& metadata) {
  if (schema_id > schema_records_.size()) {
    throw std::invalid_argument("mcap::Writer: schema " + std::to_string(schema_id) +
                                " was not added");
  }
  if (slots_.size() >= 0xFFFF) throw RecordingError(path_ + ": too many channels");
  const auto id = static_cast<std::uint16_t>(slots_.size() + 1);
  scratch_.clear();
  ByteWriter w(scratch_);
  const std::size_t at = w.begin_record(kOpChannel);
  w.u16(id);
  w.u16(schema_id);
  w.str(topic);
  w.str(message_encoding);
  put_map(w, metadata);
  w.end_record(at);
  write_data_record(kChannel);
  channel_records_.push_back(scratch_);
  slots_.emplace_back();
  slots_.back().index.reserve(1024);
  return id;
}

void Writer::add_metadata(std::string_view name, const KeyValues& entries) {
  scratch_.clear();
  ByteWriter w(scratch_);
  const std::size_t at = w.begin_record(kOpMetadata);
  w.str(name);
  put_map(w, entries);
  w.end_record(at);
  const std::uint64_t where = offset_;
  write_data_record(kMetadata);
  metadata_at_.emplace_back(where, scratch_.size());
  metadata_names_.emplace_back(name);
}

void Writer::add_message(std::uint16_t channel_id, std::uint32_t sequence,
                         std::uint64_t log_time_ns, std::uint64_t publish_time_ns,
                         const std::uint8_t* data, std::size_t size,
                         const std::uint8_t* writer_guid) {
  if (failed_ || closed_) throw RecordingError(path_ + ": the recording is closed");
  ChannelSlot& s = slot(channel_id);
  ByteWriter w(chunk_);
  if (chunk_messages_ == 0) {
    chunk_opened_ns_ = steady_ns();
    chunk_start_ns_ = chunk_end_ns_ = log_time_ns;
  }
  if (writer_guid && (!s.writer_known || std::memcmp(s.guid, writer_guid, 16) != 0)) {
    std::memcpy(s.guid, writer_guid, 16);
    s.writer_known = true;
    const std::size_t at = w.begin_record(kOpWriter);
    w.u16(channel_id);
    w.raw(writer_guid, 16);
    w.end_record(at);
  }
  s.index.emplace_back(log_time_ns, chunk_.size());
  const std::size_t at = w.begin_record(kOpMessage);
  w.u16(channel_id);
  w.u32(sequence);
  w.u64(log_time_ns);
  w.u64(publish_time_ns);
  w.raw(data, size);
  w.end_record(at);
  ++chunk_messages_;
  chunk_start_ns_ = std::min(chunk_start_ns_, log_time_ns);
  chunk_end_ns_ = std::max(chunk_end_ns_, log_time_ns);
  message_bytes_ += size;
  if (chunk_.size() >= options_.chunk_bytes) {
    flush();
  } else {
    tick();
  }
}

void Writer::tick() {
  if (chunk_messages_ > 0 && steady_ns() - chunk_opened_ns_ >= options_.chunk_ns) flush();
}

void Writer::flush() {
  if (failed_ || closed_ || chunk_messages_ == 0) return;
  try {
    write_chunk();
  } catch (const IoFailure& e) {
    fail(std::strerror(e.err));
  }
}

void Writer::write_chunk() {
  const std::size_t n = chunk_.size();
  const std::uint32_t crc = crc32(chunk_.data(), n);
  zbuf_.resize(ZSTD_compressBound(n));
  const std::size_t z = ZSTD_compressCCtx(static_cast<ZSTD_CCtx*>(cctx_), zbuf_.data(),
                                          zbuf_.size(), chunk_.data(), n, options_.zstd_level);
  if (ZSTD_isError(z)) fail(std::string("zstd: ") + ZSTD_getErrorName(z));
  ChunkEntry e;
  e.start_ns = chunk_start_ns_;
  e.end_ns = chunk_end_ns_;
  e.offset = offset_;
  e.compressed = z;
  e.uncompressed = n;
  e.messages = chunk_messages_;
  scratch_.clear();
  ByteWriter h(scratch_);
  const std::size_t at = h.begin_record(kOpChunk);
  h.u64(chunk_start_ns_);
  h.u64(chunk_end_ns_);
  h.u64(n);
  h.u32(crc);
  h.str("zstd");
  h.u64(z);
  h.patch_u64(at, scratch_.size() - at - 8 + z);
  e.length = scratch_.size() + z;
  // one Message Index record per channel with messages in the chunk, in channel order
  index_.clear();
  ByteWriter ix(index_);
  for (std::size_t c = 0; c < slots_.size(); ++c) {
    ChannelSlot& s = slots_[c];
    if (s.index.empty()) continue;
    const auto id = static_cast<std::uint16_t>(c + 1);
    e.index_offsets.emplace_back(id, e.offset + e.length + index_.size());
    e.counts.emplace_back(id, s.index.size());
    const std::size_t rec = ix.begin_record(kOpMessageIndex);
    ix.u16(id);
    const std::size_t arr = ix.begin_group();
    for (const auto& [t, off] : s.index) {
      ix.u64(t);
      ix.u64(off);
    }
    ix.end_group(arr);
    ix.end_record(rec);
  }
  e.index_length = index_.size();
  write_bytes(scratch_.data(), scratch_.size());
  write_bytes(zbuf_.data(), z);
  write_bytes(index_.data(), index_.size());
  messages_in_file_ += chunk_messages_;
  chunks_.push_back(std::move(e));
  mark_boundary(kChunk);
  chunk_.clear();
  chunk_messages_ = 0;
  for (ChannelSlot& s : slots_) {
    s.index.clear();
    s.writer_known = false;
  }
}

/// One Chunk Index record per chunk written.
void Writer::put_chunk_indexes(ByteWriter& w) const {
  for (const ChunkEntry& c : chunks_) {
    const std::size_t rec = w.begin_record(kOpChunkIndex);
    w.u64(c.start_ns);
    w.u64(c.end_ns);
    w.u64(c.offset);
    w.u64(c.length);
    const std::size_t map = w.begin_group();
    for (const auto& [id, off] : c.index_offsets) {
      w.u16(id);
      w.u64(off);
    }
    w.end_group(map);
    w.u64(c.index_length);
    w.str("zstd");
    w.u64(c.compressed);
    w.u64(c.uncompressed);
    w.end_record(rec);
  }
}

/// One Metadata Index record per Metadata record written.
void Writer::put_metadata_indexes(ByteWriter& w) const {
  for (std::size_t i = 0; i < metadata_at_.size(); ++i) {
    const std::size_t rec = w.begin_record(kOpMetadataIndex);
    w.u64(metadata_at_[i].first);
    w.u64(metadata_at_[i].second);
    w.str(metadata_names_[i]);
    w.end_record(rec);
  }
}

/// The Statistics record: record counts, and the messages per channel and their time range
/// over the chunks written.
void Writer::put_statistics(ByteWriter& w) const {
  std::map<std::uint16_t, std::uint64_t> counts;
  std::uint64_t messages = 0, first = 0, last = 0;
  for (const ChunkEntry& c : chunks_) {
    for (const auto& [id, n] : c.counts) counts[id] += n;
    first = messages == 0 ? c.start_ns : std::min(first, c.start_ns);
    last = messages == 0 ? c.end_ns : std::max(last, c.end_ns);
    messages += c.messages;
  }
  const std::size_t rec = w.begin_record(kOpStatistics);
  w.u64(messages);
  w.u16(static_cast<std::uint16_t>(schema_records_.size()));
  w.u32(static_cast<std::uint32_t>(channel_records_.size()));
  w.u32(0);  // attachments
  w.u32(static_cast<std::uint32_t>(metadata_at_.size()));
  w.u32(static_cast<std::uint32_t>(chunks_.size()));
  w.u64(first);
  w.u64(last);
  const std::size_t map = w.begin_group();
  for (const auto& [id, n] : counts) {
    w.u16(id);
    w.u64(n);
  }
  w.end_group(map);
  w.end_record(rec);
}

std::vector<std::uint8_t> Writer::build_tail() const {
  std::vector<std::uint8_t> out;
  ByteWriter w(out);
  std::size_t at = w.begin_record(kOpDataEnd);
  w.u32(data_crc_);
  w.end_record(at);
  const std::uint64_t summary_start = offset_ + out.size();
  struct Group {
    std::uint8_t op;
    std::uint64_t start, length;
  };
  std::vector<Group> groups;
  auto group = [&](std::uint8_t op, const auto& add) {
    const std::size_t from = out.size();
    add();
    if (out.size() > from) groups.push_back({op, offset_ + from, out.size() - from});
  };
  group(kOpSchema, [&] {
    for (const auto& r : schema_records_) w.raw(r.data(), r.size());
  });
  group(kOpChannel, [&] {
    for (const auto& r : channel_records_) w.raw(r.data(), r.size());
  });
  group(kOpChunkIndex, [&] { put_chunk_indexes(w); });
  group(kOpMetadataIndex, [&] { put_metadata_indexes(w); });
  group(kOpStatistics, [&] { put_statistics(w); });
  const std::uint64_t summary_offset_start = offset_ + out.size();
  for (const Group& g : groups) {
    const std::size_t rec = w.begin_record(kOpSummaryOffset);
    w.u8(g.op);
    w.u64(g.start);
    w.u64(g.length);
    w.end_record(rec);
  }
  w.u8(kOpFooter);
  w.u64(kFooterContent);
  w.u64(summary_start);
  w.u64(summary_offset_start);
  // the summary CRC covers the summary, the summary offsets and the footer up to this field
  const std::size_t crc_from = static_cast<std::size_t>(summary_start - offset_);
  w.u32(crc32(out.data() + crc_from, out.size() - crc_from));
  w.raw(kMagic, sizeof kMagic);
  return out;
}

void Writer::write_tail() {
  const std::vector<std::uint8_t> tail = build_tail();
  write_bytes(tail.data(), tail.size());
}

void Writer::finish_after_failure() {
  chunk_.clear();
  chunk_messages_ = 0;
  for (ChannelSlot& s : slots_) s.index.clear();
  std::size_t dropped = 0;
  while (fd_ >= 0 && !boundaries_.empty()) {
    const Boundary b = boundaries_.back();
    if (::ftruncate(fd_, static_cast<off_t>(b.end)) != 0) {
      error_ += std::string("; the file could not be cut back: ") + std::strerror(errno);
      break;
    }
    offset_ = b.end;
    data_crc_ = b.crc;
    try {
      write_tail();
      error_ += "; the file was closed as a valid MCAP file holding the " +
                std::to_string(messages_in_file_) + " messages of its " +
                std::to_string(chunks_.size()) + " complete chunks";
      if (dropped > 0) {
        error_ += " (" + std::to_string(dropped) + " newer records dropped to make room for the " +
                  "summary)";
      }
      closed_ = true;
      ::close(fd_);
      fd_ = -1;
      return;
    } catch (const IoFailure&) {
    }
    if (boundaries_.size() == 1) break;  // only the header is left
    switch (b.kind) {
      case kChunk:
        messages_in_file_ -= chunks_.back().messages;
        chunks_.pop_back();
        break;
      case kSchema:
        schema_records_.pop_back();
        break;
      case kChannel:
        channel_records_.pop_back();
        break;
      case kMetadata:
        metadata_at_.pop_back();
        metadata_names_.pop_back();
        break;
      default:
        break;
    }
    boundaries_.pop_back();
    ++dropped;
  }
  error_ +=
      "; the file could not be finished (no room for its summary): its complete chunks "
      "are recovered when it is read";
  closed_ = true;
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

void Writer::close() {
  if (closed_) return;
  if (failed_) {
    closed_ = true;
    return;
  }
  try {
    if (chunk_messages_ > 0) write_chunk();
    write_tail();
  } catch (const IoFailure& e) {
    fail(std::strerror(e.err));
  }
  closed_ = true;
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) {
    failed_ = true;
    error_ = path_ + ": " + std::strerror(errno);
    throw RecordingError(error_);
  }
}

}  // namespace teleop::record::mcap
