// The recording file in the SQLite format: what goes in comes out, byte for byte, in receive
// order, from a seek point; a file that is not a recording is refused. (MCAP: mcap_test.cpp.)
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>

#include "common/config/config.hpp"
#include "common/record/recording.hpp"

namespace teleop::record {
namespace {

std::string tmp(const std::string& name) {
  return "/tmp/teleop_recording_test_" + std::to_string(getpid()) + "_" + name;
}

/// Writes 100 samples of two topics to `path` (its format from its name), reads them back.
void round_trip(const std::string& path, RecordingFormat format) {
  std::vector<RecordedSample> in;
  {
    RecordingWriter w(path);
    EXPECT_EQ(w.format(), format);
    const int a = w.add_topic("teleop/slave_state", "teleop::SlaveState", "stream");
    const int b = w.add_topic("teleop/mesh_frame", "teleop::MeshFrame", "stream");
    for (int i = 0; i < 100; ++i) {
      RecordedSample s;
      s.topic_id = i % 3 == 0 ? b : a;
      s.receive_ns = 1'000'000'000LL + i * 1'000'000LL;
      s.source_ns = s.receive_ns - 50'000;
      s.writer_seq = i + 1;
      s.writer_guid[15] = static_cast<std::uint8_t>(s.topic_id);
      // large, compressible payloads for one topic (zstd path), small ones for the other
      s.payload.resize(s.topic_id == b ? 30000 : 200);
      for (std::size_t k = 0; k < s.payload.size(); ++k) {
        s.payload[k] = static_cast<std::uint8_t>(s.topic_id == b ? (k / 64) : (k * 31 + i));
      }
      in.push_back(s);
    }
    w.append(in);
    w.set_meta("domain", "7");
    EXPECT_LT(w.stored_bytes(), w.raw_bytes());  // the large payloads were compressed
  }
  EXPECT_EQ(detect_format(path), format);
  RecordingReader r(path);
  EXPECT_EQ(r.format(), format);
  EXPECT_EQ(r.counts().at(r.topics()[0].id) + r.counts().at(r.topics()[1].id), 100);
  EXPECT_EQ(r.verify_file(), "ok");
  ASSERT_EQ(r.topics().size(), 2u);
  EXPECT_EQ(r.topics()[1].type_name, "teleop::MeshFrame");
  EXPECT_EQ(r.topics()[1].qos, "stream");
  EXPECT_EQ(r.topics()[0].name, "teleop/slave_state");
  EXPECT_EQ(r.meta().at("domain"), "7");
  EXPECT_EQ(r.first_ns(), in.front().receive_ns);
  EXPECT_EQ(r.last_ns(), in.back().receive_ns);
  r.scan(in[40].receive_ns);
  RecordedSample s;
  std::size_t i = 40;
  while (r.next(s)) {
    ASSERT_LT(i, in.size());
    EXPECT_EQ(s.receive_ns, in[i].receive_ns);
    EXPECT_EQ(s.source_ns, in[i].source_ns);
    EXPECT_EQ(s.writer_seq, in[i].writer_seq);
    EXPECT_EQ(s.writer_guid[15], in[i].writer_guid[15]);
    EXPECT_EQ(s.payload, in[i].payload);
    ++i;
  }
  EXPECT_EQ(i, in.size());
  // one topic, a time window
  r.scan(in[0].receive_ns, in[10].receive_ns, {r.topics()[1].id});
  int n = 0;
  while (r.next(s)) ++n;
  EXPECT_EQ(n, 4);  // samples 0, 3, 6, 9
  std::remove(path.c_str());
}

TEST(Recording, RoundTripInReceiveOrderWithSeek) {
  round_trip(tmp("a.db"), RecordingFormat::kSqlite);
  round_trip(tmp("a.mcap"), RecordingFormat::kMcap);
  round_trip(tmp("a"), RecordingFormat::kMcap);  // any other name: MCAP
}

TEST(Recording, FormatByNameAndByFirstBytes) {
  EXPECT_EQ(format_for_path("x.db"), RecordingFormat::kSqlite);
  EXPECT_EQ(format_for_path("x.sqlite"), RecordingFormat::kSqlite);
  EXPECT_EQ(format_for_path("x.sqlite3"), RecordingFormat::kSqlite);
  EXPECT_EQ(format_for_path("x.mcap"), RecordingFormat::kMcap);
  EXPECT_EQ(format_for_path("x.db.mcap"), RecordingFormat::kMcap);
  EXPECT_EQ(parse_format("--format", "sqlite"), RecordingFormat::kSqlite);
  EXPECT_THROW(parse_format("--format", "bag"), config::ConfigError);
  // an MCAP file named .db is still read as MCAP: the first bytes decide
  const std::string path = tmp("really_mcap.db");
  {
    RecordingWriter w(path, RecordingFormat::kMcap);
    w.add_topic("teleop/events", "teleop::Event", "event_log");
  }
  EXPECT_EQ(detect_format(path), RecordingFormat::kMcap);
  RecordingReader r(path);
  EXPECT_EQ(r.format(), RecordingFormat::kMcap);
  EXPECT_EQ(r.topics().at(0).qos, "event_log");
  std::remove(path.c_str());
}

/// The file offset of the first occurrence of `needle` in the file at `path`; npos if none.
std::size_t find_in_file(const std::string& path, const std::string& needle) {
  std::ifstream f(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  return bytes.find(needle);
}

TEST(Recording, AFlippedPayloadByteInASqliteRecordingIsRefusedNamingTheSample) {
  const std::string path = tmp("flip.db");
  const std::string marker = "payload-marker-0123456789";  // stored raw (under 512 bytes)
  {
    RecordingWriter w(path);
    const int a = w.add_topic("teleop/slave_state", "teleop::SlaveState", "stream");
    std::vector<RecordedSample> in(3);
    for (std::size_t i = 0; i < in.size(); ++i) {
      in[i].topic_id = a;
      in[i].receive_ns = 1'000'000'000LL + static_cast<std::int64_t>(i) * 1'000'000LL;
      const std::string text = i == 1 ? marker : "other-sample-" + std::to_string(i);
      in[i].payload.assign(text.begin(), text.end());
    }
    w.append(in);
  }
  {
    RecordingReader r(path);
    EXPECT_EQ(r.health().how, "SQLite, a CRC-32 per sample");
    r.scan(0);
    RecordedSample s;
    int n = 0;
    while (r.next(s)) ++n;
    EXPECT_EQ(n, 3);
  }
  // flip one bit of the marker inside the file (the database stays well-formed)
  const std::size_t at = find_in_file(path, marker);
  ASSERT_NE(at, std::string::npos);
  {
    std::fstream f(path, std::ios::binary | std::ios::in | std::ios::out);
    f.seekp(static_cast<std::streamoff>(at + 3));
    f.put(static_cast<char>(marker[3] ^ 0x01));
  }
  RecordingReader r(path);
  EXPECT_EQ(r.verify_file(), "ok");  // SQLite's own check does not see a payload byte
  r.scan(0);
  RecordedSample s;
  ASSERT_TRUE(r.next(s));  // the first sample is intact
  try {
    r.next(s);
    FAIL() << "the damaged sample was read without an error";
  } catch (const config::ConfigError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find("samples.crc32"), std::string::npos) << msg;
    EXPECT_NE(msg.find("receive_ns 1001000000"), std::string::npos) << msg;
  }
  std::remove(path.c_str());
}

TEST(Recording, NotARecordingIsRefused) {
  const std::string path = tmp("b.db");
  { std::ofstream(path) << "hello"; }
  EXPECT_THROW(RecordingReader r(path), RecordingError);
  EXPECT_THROW(RecordingReader r(tmp("missing.db")), RecordingError);
  std::remove(path.c_str());
}

}  // namespace
}  // namespace teleop::record
