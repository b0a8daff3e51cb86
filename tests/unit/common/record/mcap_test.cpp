// The MCAP writer and reader (common/record/mcap_*.hpp): the layout the specification asks for,
// seeking through the chunk index, log-time order across chunks, recovery of every complete
// chunk of a file cut anywhere, CRC checks, hostile bytes, and a full disk that still leaves a
// valid file.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "common/config/config.hpp"
#include "common/record/crc32.hpp"
#include "common/record/mcap_format.hpp"
#include "common/record/mcap_reader.hpp"
#include "common/record/mcap_recording.hpp"
#include "common/record/mcap_writer.hpp"
#include "common/record/recording.hpp"
#include "idl/idl_text.hpp"
#include "tests/support/alloc_counter.hpp"

namespace teleop::record::mcap {
namespace {

std::string tmp(const std::string& name) {
  return "/tmp/teleop_mcap_test_" + std::to_string(getpid()) + "_" + name;
}

std::vector<std::uint8_t> slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

struct Sent {
  std::uint16_t channel;
  std::uint64_t log_ns;
  std::uint32_t seq;
  std::vector<std::uint8_t> data;
};

/// A payload that tells its message apart (and compresses a little).
std::vector<std::uint8_t> payload(std::uint32_t i, std::size_t n) {
  std::vector<std::uint8_t> p(n);
  for (std::size_t k = 0; k < n; ++k) p[k] = static_cast<std::uint8_t>((k / 7) ^ (i * 13));
  std::memcpy(p.data(), &i, sizeof i);
  return p;
}

/// Writes `n` messages on two channels, 1 ms apart, into chunks of about `chunk_bytes`.
std::vector<Sent> write_file(const std::string& path, int n, std::uint64_t chunk_bytes,
                             std::uint64_t* messages_in_file = nullptr) {
  WriterOptions o;
  o.chunk_bytes = chunk_bytes;
  o.chunk_ns = std::int64_t{1} << 62;  // by size only: the test is independent of timing
  Writer w(path, o);
  const std::uint16_t s = w.add_schema("teleop::SlaveState", "omgidl", "module teleop {};");
  const std::uint16_t a = w.add_channel(s, "teleop/slave_state", "cdr", {{"qos", "stream"}});
  const std::uint16_t b = w.add_channel(s, "teleop/slave_state_view", "cdr", {{"qos", "latest"}});
  w.add_metadata("teleop_record", {{"domain", "9"}});
  std::vector<Sent> sent;
  std::uint8_t guid[16] = {1, 2, 3};
  for (int i = 0; i < n; ++i) {
    Sent m{i % 4 == 0 ? b : a, 1'000'000'000ULL + static_cast<std::uint64_t>(i) * 1'000'000ULL,
           static_cast<std::uint32_t>(i + 1), payload(static_cast<std::uint32_t>(i), 100 + i % 50)};
    guid[15] = static_cast<std::uint8_t>(i / 100);  // the writer changes every 100 messages
    w.add_message(m.channel, m.seq, m.log_ns, m.log_ns - 1000, m.data.data(), m.data.size(), guid);
    sent.push_back(std::move(m));
  }
  w.close();
  if (messages_in_file) *messages_in_file = w.messages_in_file();
  return sent;
}

std::vector<Sent> read_all(Reader& r, std::uint64_t from = 0, std::uint64_t to = 0,
                           const std::vector<std::uint16_t>& channels = {}) {
  std::vector<Sent> got;
  r.scan(from, to, channels);
  MessageView m;
  while (r.next(m)) {
    got.push_back({m.channel_id, m.log_time_ns, m.sequence, {m.data, m.data + m.size}});
    EXPECT_EQ(m.publish_time_ns, m.log_time_ns - 1000);
    EXPECT_NE(m.writer_guid, nullptr);
    if (m.writer_guid) {
      EXPECT_EQ(m.writer_guid[15], (m.sequence - 1) / 100);
    }
  }
  return got;
}

TEST(Crc32, MatchesTheStandardCheckValue) {
  EXPECT_EQ(crc32("123456789", 9), 0xCBF43926u);  // CRC-32/ISO-HDLC check value
  EXPECT_EQ(crc32("", 0), 0u);
  const std::string text = "The quick brown fox jumps over the lazy dog, twice over again.";
  EXPECT_EQ(crc32_update(crc32(text.data(), 10), text.data() + 10, text.size() - 10),
            crc32(text.data(), text.size()));
  EXPECT_EQ(crc32("The quick brown fox jumps over the lazy dog", 43), 0x414FA339u);
}

TEST(IdlText, EachTopicTypeHasTheIdlFileThatDefinesIt) {
  const auto slave = idl::idl_text_for_type("teleop::SlaveState");
  EXPECT_NE(slave.find("struct SlaveState"), std::string_view::npos);
  EXPECT_NE(slave.find("module teleop"), std::string_view::npos);
  EXPECT_NE(idl::idl_text_for_type("teleop::DeviceState").find("struct DeviceState"),
            std::string_view::npos);
  EXPECT_TRUE(idl::idl_text_for_type("teleop::Nope").empty());
  EXPECT_TRUE(idl::idl_text_for_type("other::SlaveState").empty());
}

TEST(Mcap, FileLayoutFollowsTheSpecification) {
  const std::string path = tmp("layout.mcap");
  const auto sent = write_file(path, 2000, 16 << 10);
  const auto bytes = slurp(path);
  ASSERT_GT(bytes.size(), 64u);
  EXPECT_EQ(std::memcmp(bytes.data(), kMagic, 8), 0);
  EXPECT_EQ(std::memcmp(bytes.data() + bytes.size() - 8, kMagic, 8), 0);
  EXPECT_EQ(bytes[8], kOpHeader);
  EXPECT_EQ(bytes[bytes.size() - 8 - 29], kOpFooter);
  Reader r(path);
  EXPECT_TRUE(r.health().indexed);
  EXPECT_FALSE(r.health().recovered);
  ASSERT_EQ(r.schemas().size(), 1u);
  EXPECT_EQ(r.schemas().at(1).encoding, "omgidl");
  EXPECT_EQ(r.schemas().at(1).name, "teleop::SlaveState");
  ASSERT_EQ(r.channels().size(), 2u);
  EXPECT_EQ(r.channels().at(1).message_encoding, "cdr");
  EXPECT_EQ(r.channels().at(2).metadata.at(0).second, "latest");
  EXPECT_GT(r.chunks().size(), 5u);
  EXPECT_EQ(r.channel_counts().at(1) + r.channel_counts().at(2), 2000u);
  EXPECT_EQ(r.channel_counts().at(2), 500u);
  EXPECT_EQ(r.start_ns(), sent.front().log_ns);
  EXPECT_EQ(r.end_ns(), sent.back().log_ns);
  ASSERT_EQ(r.metadata().size(), 1u);
  EXPECT_EQ(r.metadata()[0].entries.at(0).second, "9");
  EXPECT_EQ(r.verify_data_crc(), "ok");
  const auto got = read_all(r);
  ASSERT_EQ(got.size(), sent.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].log_ns, sent[i].log_ns);
    EXPECT_EQ(got[i].seq, sent[i].seq);
    EXPECT_EQ(got[i].channel, sent[i].channel);
    EXPECT_EQ(got[i].data, sent[i].data);
  }
  std::remove(path.c_str());
}

TEST(Mcap, ASeekReadsOnlyTheChunksOfItsWindow) {
  const std::string path = tmp("seek.mcap");
  const auto sent = write_file(path, 4000, 8 << 10);
  Reader r(path);
  const std::size_t chunks = r.chunks().size();
  ASSERT_GT(chunks, 20u);
  // the last tenth of the recording
  const std::uint64_t from = sent[3600].log_ns;
  const auto got = read_all(r, from);
  ASSERT_EQ(got.size(), 400u);
  EXPECT_EQ(got.front().seq, sent[3600].seq);
  EXPECT_LE(r.chunks_loaded(), chunks / 10 + 3);
  // a window on one channel
  const std::uint64_t loaded = r.chunks_loaded();
  const auto window = read_all(r, sent[1000].log_ns, sent[1100].log_ns, {2});
  EXPECT_EQ(window.size(), 25u);  // every fourth message is on channel 2
  EXPECT_LE(r.chunks_loaded() - loaded, 6u);
  std::remove(path.c_str());
}

TEST(Mcap, MessagesComeInLogTimeOrderAcrossOverlappingChunks) {
  const std::string path = tmp("overlap.mcap");
  {
    WriterOptions o;
    o.chunk_bytes = 2000;
    o.chunk_ns = std::int64_t{1} << 62;
    Writer w(path, o);
    const std::uint16_t c = w.add_channel(0, "t", "cdr", {});
    // batches as a recorder takes them: topic by topic, so times go back at each batch
    std::vector<std::uint8_t> data(40, 7);
    for (int batch = 0; batch < 50; ++batch) {
      for (int k = 0; k < 30; ++k) {
        const std::uint64_t t = 1000000 + static_cast<std::uint64_t>(batch * 10 + (k * 7) % 30);
        w.add_message(c, static_cast<std::uint32_t>(batch * 30 + k), t, t, data.data(), data.size(),
                      nullptr);
      }
    }
  }
  Reader r(path);
  ASSERT_GT(r.chunks().size(), 10u);
  r.scan(0, 0, {});
  MessageView m;
  std::uint64_t prev = 0, n = 0;
  while (r.next(m)) {
    EXPECT_GE(m.log_time_ns, prev);
    EXPECT_EQ(m.writer_guid, nullptr);
    prev = m.log_time_ns;
    ++n;
  }
  EXPECT_EQ(n, 1500u);
  std::remove(path.c_str());
}

TEST(Mcap, ACutFileKeepsEveryCompleteChunkWhereverItIsCut) {
  const std::string path = tmp("cut.mcap");
  const auto sent = write_file(path, 1500, 4 << 10);
  const auto bytes = slurp(path);
  std::vector<ChunkInfo> chunks;
  {
    Reader whole(path);
    chunks = whole.chunks();
  }
  ASSERT_GT(chunks.size(), 8u);
  // messages in the chunks wholly before `cut`, in file order (log order here)
  auto expected = [&](std::uint64_t cut) {
    std::uint64_t n = 0;
    for (const ChunkInfo& c : chunks) {
      if (c.offset + c.length <= cut) n += (c.end_ns - c.start_ns) / 1'000'000 + 1;
    }
    return n;
  };
  std::vector<std::uint64_t> cuts;
  for (std::uint64_t c = 0; c < bytes.size(); c += 61) cuts.push_back(c);
  for (const ChunkInfo& c : chunks) {
    for (std::int64_t d = -10; d <= 10; ++d) {
      cuts.push_back(
          static_cast<std::uint64_t>(static_cast<std::int64_t>(c.offset + c.length) + d));
    }
  }
  int opened = 0;
  for (const std::uint64_t cut : cuts) {
    if (cut > bytes.size()) continue;
    try {
      Reader r(bytes.data(), static_cast<std::size_t>(cut), "cut");
      ++opened;
      const auto got = read_all(r);
      if (cut == bytes.size()) {
        EXPECT_TRUE(r.health().indexed);
        EXPECT_EQ(got.size(), sent.size());
        continue;
      }
      EXPECT_TRUE(r.health().recovered) << cut;
      // cut inside the data section: exactly the complete chunks; after it: everything
      const std::uint64_t want =
          cut >= chunks.back().offset + chunks.back().length ? sent.size() : expected(cut);
      ASSERT_EQ(got.size(), want) << "cut at " << cut << ": " << r.health().note;
      for (std::size_t i = 0; i < got.size(); ++i) {
        ASSERT_EQ(got[i].seq, sent[i].seq) << cut;
        ASSERT_EQ(got[i].data, sent[i].data) << cut;
      }
    } catch (const config::ConfigError& e) {
      // only a file cut inside its magic and Header record is refused
      EXPECT_LT(cut, 8u + 9u + 64u) << e.what();
    }
  }
  EXPECT_GT(opened, 100);
  std::remove(path.c_str());
}

TEST(Mcap, ACutChunkCountsTheMessagesItLoses) {
  const std::string path = tmp("lost.mcap");
  write_file(path, 1000, 1 << 20);  // one chunk
  const auto bytes = slurp(path);
  Reader whole(path);
  ASSERT_EQ(whole.chunks().size(), 1u);
  const ChunkInfo c = whole.chunks()[0];
  Reader cut(bytes.data(), static_cast<std::size_t>(c.offset + c.length - 100), "cut");
  EXPECT_TRUE(cut.health().recovered);
  EXPECT_EQ(cut.health().dropped_chunks, 1u);
  EXPECT_GT(cut.health().dropped_messages, 100u);  // most of it decodes before the cut
  EXPECT_LE(cut.health().dropped_messages, 1000u);
  EXPECT_EQ(read_all(cut).size(), 0u);
  std::remove(path.c_str());
}

/// The offset of the first byte of `chunk`'s compressed records.
std::uint64_t records_at(const std::vector<std::uint8_t>& bytes, const ChunkInfo& c) {
  const std::uint64_t at = c.offset + kRecordPrefix + 8 + 8 + 8 + 4;
  std::uint32_t n = 0;
  std::memcpy(&n, bytes.data() + at, 4);
  return at + 4 + n + 8;
}

TEST(Mcap, ACorruptChunkIsRefusedWithItsCrcOrDroppedInRecovery) {
  const std::string path = tmp("crc.mcap");
  const auto sent = write_file(path, 1500, 4 << 10);
  auto bytes = slurp(path);
  std::vector<ChunkInfo> chunks;
  {
    Reader r(path);
    chunks = r.chunks();
  }
  ASSERT_GT(chunks.size(), 4u);
  // the uncompressed CRC of the third chunk is wrong
  const std::uint64_t crc_at = chunks[2].offset + kRecordPrefix + 24;
  bytes[crc_at] ^= 0x55;
  {
    Reader r(bytes.data(), bytes.size(), "crc");
    EXPECT_TRUE(r.health().indexed);
    try {
      read_all(r);
      ADD_FAILURE() << "a wrong chunk CRC was not noticed";
    } catch (const config::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("uncompressed_crc"), std::string::npos) << e.what();
      EXPECT_NE(
          std::string(e.what()).find("Chunk record at byte " + std::to_string(chunks[2].offset)),
          std::string::npos)
          << e.what();
    }
    // the data section's CRC covers it too
    EXPECT_THROW(r.verify_data_crc(), config::ConfigError);
  }
  // without the summary (footer gone) the damaged chunk is dropped and the others kept
  {
    std::vector<std::uint8_t> no_footer(bytes.begin(), bytes.end() - 20);
    Reader r(no_footer.data(), no_footer.size(), "no footer");
    EXPECT_TRUE(r.health().recovered);
    EXPECT_EQ(r.health().dropped_chunks, 1u);
    EXPECT_NE(r.health().note.find("uncompressed_crc"), std::string::npos) << r.health().note;
    const auto got = read_all(r);
    const std::uint64_t lost = (chunks[2].end_ns - chunks[2].start_ns) / 1'000'000 + 1;
    EXPECT_EQ(got.size(), sent.size() - lost);
  }
  // a flipped byte inside the compressed records
  bytes[crc_at] ^= 0x55;
  bytes[records_at(bytes, chunks[3]) + 40] ^= 0xFF;
  {
    Reader r(bytes.data(), bytes.size(), "zstd");
    EXPECT_THROW(read_all(r), config::ConfigError);
  }
  std::remove(path.c_str());
}

TEST(Mcap, ADamagedSummaryFallsBackToTheDataSection) {
  const std::string path = tmp("summary.mcap");
  const auto sent = write_file(path, 800, 4 << 10);
  auto bytes = slurp(path);
  // a byte of the last Chunk Index record, before the footer
  bytes[bytes.size() - 8 - 29 - 200] ^= 0x01;
  Reader r(bytes.data(), bytes.size(), "summary");
  EXPECT_TRUE(r.health().recovered);
  EXPECT_NE(r.health().note.find("CRC"), std::string::npos) << r.health().note;
  EXPECT_EQ(read_all(r).size(), sent.size());
  std::remove(path.c_str());
}

/// Appends a record to `out`.
void record(std::vector<std::uint8_t>& out, std::uint8_t op, const std::vector<std::uint8_t>& c) {
  ByteWriter w(out);
  w.u8(op);
  w.u64(c.size());
  w.raw(c.data(), c.size());
}

std::vector<std::uint8_t> header_only() {
  std::vector<std::uint8_t> out(kMagic, kMagic + 8);
  std::vector<std::uint8_t> h;
  ByteWriter w(h);
  w.str("");
  w.str("test");
  record(out, kOpHeader, h);
  return out;
}

/// Opens `bytes` and reads every message; returns the error text, or "" when it read.
std::string open_and_read(const std::vector<std::uint8_t>& bytes) {
  try {
    Reader r(bytes.data(), bytes.size(), "hostile");
    r.channel_counts();
    r.verify_data_crc();
    r.scan(0, 0, {});
    MessageView m;
    while (r.next(m)) {
    }
    return "";
  } catch (const config::ConfigError& e) {
    return e.what();
  }
}

/// A file with a chunk that claims 2^40 uncompressed bytes.
std::vector<std::uint8_t> chunk_claiming_a_terabyte() {
  auto big = header_only();
  std::vector<std::uint8_t> c;
  ByteWriter cw(c);
  cw.u64(1);
  cw.u64(2);
  cw.u64(std::uint64_t{1} << 40);
  cw.u32(0);
  cw.str("zstd");
  cw.u64(4);
  cw.u32(0xFD2FB528);
  record(big, kOpChunk, c);
  return big;
}

/// A file with a chunk compressed with lz4 (unknown to the reader).
std::vector<std::uint8_t> chunk_in_lz4() {
  auto lz4 = header_only();
  std::vector<std::uint8_t> c;
  ByteWriter cw(c);
  cw.u64(1);
  cw.u64(2);
  cw.u64(4);
  cw.u32(0);
  cw.str("lz4");
  cw.u64(4);
  cw.u32(0);
  record(lz4, kOpChunk, c);
  return lz4;
}

/// A file with a message on a channel nobody defined, inside an uncompressed chunk.
std::vector<std::uint8_t> message_without_channel() {
  auto orphan = header_only();
  std::vector<std::uint8_t> recs;
  std::vector<std::uint8_t> msg;
  ByteWriter mw(msg);
  mw.u16(9);
  mw.u32(1);
  mw.u64(5);
  mw.u64(5);
  record(recs, kOpMessage, msg);
  std::vector<std::uint8_t> c;
  ByteWriter cw(c);
  cw.u64(5);
  cw.u64(5);
  cw.u64(recs.size());
  cw.u32(crc32(recs.data(), recs.size()));
  cw.str("");
  cw.u64(recs.size());
  cw.raw(recs.data(), recs.size());
  record(orphan, kOpChunk, c);
  return orphan;
}

/// A file whose footer points outside it.
std::vector<std::uint8_t> footer_pointing_outside() {
  auto footer = header_only();
  std::vector<std::uint8_t> f;
  ByteWriter fw(f);
  fw.u64(std::uint64_t{1} << 50);
  fw.u64(7);
  fw.u32(0);
  record(footer, kOpFooter, f);
  footer.insert(footer.end(), kMagic, kMagic + 8);
  return footer;
}

/// A file with a Channel record whose metadata map is longer than the record.
std::vector<std::uint8_t> channel_map_past_its_record() {
  auto channel = header_only();
  std::vector<std::uint8_t> ch;
  ByteWriter chw(ch);
  chw.u16(1);
  chw.u16(0);
  chw.str("t");
  chw.str("cdr");
  chw.u32(1000);  // a metadata map longer than the record
  record(channel, kOpChannel, ch);
  return channel;
}

TEST(Mcap, HostileBytesAreRefusedWithTheFieldAndItsRange) {
  // not MCAP, too short, a wrong first record
  EXPECT_NE(open_and_read({'h', 'e', 'l', 'l', 'o'}).find("too few"), std::string::npos);
  std::vector<std::uint8_t> junk(kMagic, kMagic + 8);
  junk.resize(100, 0xEE);
  EXPECT_NE(open_and_read(junk).find("Header"), std::string::npos);
  // a Header whose length runs past the end
  std::vector<std::uint8_t> long_header(kMagic, kMagic + 8);
  ByteWriter lw(long_header);
  lw.u8(kOpHeader);
  lw.u64(std::uint64_t{1} << 60);
  EXPECT_NE(open_and_read(long_header).find("field 'length'"), std::string::npos);
  // a chunk that claims 2^40 uncompressed bytes
  const auto big = chunk_claiming_a_terabyte();
  Reader big_reader(big.data(), big.size(), "big");
  EXPECT_EQ(big_reader.health().dropped_chunks, 1u);
  EXPECT_NE(big_reader.health().note.find("uncompressed_size"), std::string::npos)
      << big_reader.health().note;
  // an unknown compression
  const auto lz4 = chunk_in_lz4();
  Reader lz4_reader(lz4.data(), lz4.size(), "lz4");
  EXPECT_NE(lz4_reader.health().note.find("'lz4'"), std::string::npos) << lz4_reader.health().note;
  // a message on a channel nobody defined, inside an uncompressed chunk
  const auto orphan = message_without_channel();
  Reader orphan_reader(orphan.data(), orphan.size(), "orphan");
  EXPECT_NE(orphan_reader.health().note.find("channel_id"), std::string::npos)
      << orphan_reader.health().note;
  // a footer pointing outside the file, a map length past its record: no crash, an answer
  const auto footer = footer_pointing_outside();
  EXPECT_EQ(open_and_read(footer), "");
  Reader footer_reader(footer.data(), footer.size(), "footer");
  EXPECT_TRUE(footer_reader.health().recovered);
  EXPECT_NE(open_and_read(channel_map_past_its_record()).find("field 'metadata'"),
            std::string::npos);
}

TEST(Mcap, AddingAMessageDoesNotAllocate) {
  const std::string path = tmp("alloc.mcap");
  WriterOptions o;
  o.chunk_bytes = 1 << 20;
  o.chunk_ns = std::int64_t{1} << 62;
  Writer w(path, o);
  const std::uint16_t c = w.add_channel(0, "t", "cdr", {});
  std::vector<std::uint8_t> data(300, 1);
  std::uint8_t guid[16] = {9};
  for (int i = 0; i < 2000; ++i) w.add_message(c, 1, 10 + i, 10, data.data(), data.size(), guid);
  w.flush();  // the buffers have grown to a chunk's size
  std::uint64_t allocations = 0;
  {
    test::NoAllocScope scope;
    for (int i = 0; i < 2000; ++i) {
      guid[0] = static_cast<std::uint8_t>(i % 2);  // a writer record each time
      w.add_message(c, 1, 5000 + i, 10, data.data(), data.size(), guid);
    }
    allocations = scope.allocations();
  }
  EXPECT_EQ(allocations, 0u);
  w.close();
  std::remove(path.c_str());
}

TEST(Mcap, ChunksCloseByAge) {
  const std::string path = tmp("age.mcap");
  {
    WriterOptions o;
    o.chunk_ns = 0;  // every tick closes the open chunk
    Writer w(path, o);
    const std::uint16_t c = w.add_channel(0, "t", "cdr", {});
    std::uint8_t d = 1;
    for (int i = 0; i < 5; ++i) w.add_message(c, 1, 10 + i, 10, &d, 1, nullptr);
    EXPECT_EQ(w.chunks_in_file(), 5u);
    EXPECT_EQ(w.messages_in_file(), 5u);
  }
  Reader r(path);
  EXPECT_EQ(r.chunks().size(), 5u);
  std::remove(path.c_str());
}

/// In a child process limited to `limit` bytes per file (SIGXFSZ ignored: writes fail with
/// EFBIG, as on a full disk), writes messages until the writer fails. Returns what the child
/// reported: the writer's messages_in_file() after the failure, or -1.
long long write_until_full(const std::string& path, rlim_t limit) {
  int fds[2];
  if (::pipe(fds) != 0) return -1;
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(fds[0]);
    std::signal(SIGXFSZ, SIG_IGN);
    rlimit rl{limit, limit};
    ::setrlimit(RLIMIT_FSIZE, &rl);
    long long in_file = -1;
    try {
      RecordingWriter w(path, RecordingFormat::kMcap, McapOptions{8 << 10, 1'000'000'000, 1});
      const int a = w.add_topic("teleop/slave_state", "teleop::SlaveState", "stream");
      w.set_meta("domain", "5");
      std::vector<RecordedSample> batch(10);
      for (int i = 0; i < 200000; ++i) {
        for (int k = 0; k < 10; ++k) {
          batch[k].topic_id = a;
          batch[k].receive_ns = 1'000'000'000LL + (i * 10 + k) * 100'000LL;
          batch[k].source_ns = batch[k].receive_ns;
          batch[k].writer_seq = i * 10 + k + 1;
          batch[k].payload = payload(static_cast<std::uint32_t>(i * 10 + k), 300);
        }
        try {
          w.append(batch);
        } catch (const RecordingError& e) {
          in_file = static_cast<long long>(w.samples_in_file());
          const std::string what = e.what();
          // the message names the file, the reason and how it was finished
          if (what.find(path) == std::string::npos ||
              what.find("valid MCAP file") == std::string::npos) {
            in_file = -2;
          }
          break;
        }
      }
    } catch (...) {
      in_file = -3;
    }
    (void)!::write(fds[1], &in_file, sizeof in_file);
    ::_exit(0);
  }
  ::close(fds[1]);
  long long in_file = -1;
  if (::read(fds[0], &in_file, sizeof in_file) != sizeof in_file) in_file = -1;
  ::close(fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return in_file;
}

TEST(Mcap, AFullDiskGivesAnErrorAndAValidFile) {
  for (const rlim_t limit : {rlim_t{200} << 10, rlim_t{61} << 10}) {
    const std::string path = tmp("full.mcap");
    const long long in_file = write_until_full(path, limit);
    ASSERT_GT(in_file, 0) << "limit " << limit;
    const auto bytes = slurp(path);
    EXPECT_LE(bytes.size(), limit);
    RecordingReader r(path);
    EXPECT_FALSE(r.health().recovered) << r.health().note;  // a valid file: read by its summary
    EXPECT_EQ(r.verify_file(), "ok");
    EXPECT_EQ(r.meta().at("domain"), "5");
    std::int64_t n = 0, prev = 0;
    RecordedSample s;
    r.scan(0);
    while (r.next(s)) {
      EXPECT_EQ(s.writer_seq, ++prev);  // the first samples, none missing
      ++n;
    }
    EXPECT_EQ(n, in_file);
    std::remove(path.c_str());
  }
}

}  // namespace
}  // namespace teleop::record::mcap
