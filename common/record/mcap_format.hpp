#pragma once
// MCAP (https://mcap.dev/spec, major version 0) as this project writes and reads it: the magic,
// the record opcodes, little-endian field encoding, and the limits a reader holds an untrusted
// file to. Written from the specification; no MCAP library is used.
//
// One extension record, allowed by the specification (opcodes 0x80-0xFF are for applications,
// and readers skip records they do not know): kOpWriter (0x80) inside a chunk says which DDS
// writer (its 16-byte GUID) wrote the messages of a channel that follow it in that chunk,
//   channel_id uint16, writer_guid 16 bytes.
// It is written before a channel's first message in each chunk and again whenever that
// channel's writer changes, so every chunk stands alone (seeking, recovery). Other MCAP readers
// (Foxglove, Lichtblick, @mcap/core) ignore it.
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <vector>

namespace teleop::record::mcap {

inline constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

enum Opcode : std::uint8_t {
  kOpHeader = 0x01,
  kOpFooter = 0x02,
  kOpSchema = 0x03,
  kOpChannel = 0x04,
  kOpMessage = 0x05,
  kOpChunk = 0x06,
  kOpMessageIndex = 0x07,
  kOpChunkIndex = 0x08,
  kOpAttachment = 0x09,
  kOpAttachmentIndex = 0x0A,
  kOpStatistics = 0x0B,
  kOpMetadata = 0x0C,
  kOpMetadataIndex = 0x0D,
  kOpSummaryOffset = 0x0E,
  kOpDataEnd = 0x0F,
  kOpWriter = 0x80,  ///< this project's extension: the DDS writer of the following messages
};

/// Bytes of a record's opcode and length prefix.
inline constexpr std::uint64_t kRecordPrefix = 9;
/// Bytes of a Footer record's content (summary_start, summary_offset_start, summary_crc).
inline constexpr std::uint64_t kFooterContent = 20;
/// Bytes of a Message record's content before its data.
inline constexpr std::uint64_t kMessageHeader = 2 + 4 + 8 + 8;

/// What a reader accepts from an untrusted file.
#ifdef FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION
inline constexpr std::uint64_t kMaxChunkBytes = std::uint64_t{1} << 20;  ///< a fuzz input is small
#else
inline constexpr std::uint64_t kMaxChunkBytes = std::uint64_t{128} << 20;  ///< uncompressed
#endif
inline constexpr std::uint64_t kMaxRecordBytes = std::uint64_t{128} << 20;  ///< outside chunks
inline constexpr std::uint64_t kMaxSummaryBytes = std::uint64_t{256} << 20;

/// Appends little-endian fields to a byte vector (the buffer keeps its capacity across clear()).
class ByteWriter {
 public:
  explicit ByteWriter(std::vector<std::uint8_t>& out) : out_(out) {}
  void u8(std::uint8_t v) { out_.push_back(v); }
  void u16(std::uint16_t v) { raw(&v, 2); }
  void u32(std::uint32_t v) { raw(&v, 4); }
  void u64(std::uint64_t v) { raw(&v, 8); }
  void str(std::string_view s) {
    u32(static_cast<std::uint32_t>(s.size()));
    raw(s.data(), s.size());
  }
  void raw(const void* p, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    out_.insert(out_.end(), b, b + n);
  }
  /// Writes an opcode and a placeholder length; end_record(at) fills the length in.
  std::size_t begin_record(std::uint8_t op) {
    u8(op);
    const std::size_t at = out_.size();
    u64(0);
    return at;
  }
  void end_record(std::size_t at) { patch_u64(at, out_.size() - at - 8); }
  /// Starts a uint32 length-prefixed group (a map or an array); end_group(at) fills it in.
  std::size_t begin_group() {
    const std::size_t at = out_.size();
    u32(0);
    return at;
  }
  void end_group(std::size_t at) {
    const auto n = static_cast<std::uint32_t>(out_.size() - at - 4);
    std::memcpy(out_.data() + at, &n, 4);
  }
  void patch_u64(std::size_t at, std::uint64_t v) { std::memcpy(out_.data() + at, &v, 8); }
  std::size_t size() const { return out_.size(); }

 private:
  std::vector<std::uint8_t>& out_;
};

}  // namespace teleop::record::mcap
