#include "common/record/sqlite_recording.hpp"

#include <sqlite3.h>
#include <zstd.h>

#include <cstdio>
#include <cstring>

#include "common/config/config.hpp"
#include "common/record/crc32.hpp"

namespace teleop::record {

namespace {

constexpr int kCodecRaw = 0;
constexpr int kCodecZstd = 1;
constexpr std::size_t kCompressFrom = 512;  // smaller payloads do not shrink enough
constexpr const char* kFormat = "teleop-recording-1";

[[noreturn]] void fail(sqlite3* db, const std::string& what) {
  throw RecordingError(what + ": " + (db ? sqlite3_errmsg(db) : "out of memory"));
}

void check(sqlite3* db, int rc, const std::string& what) {
  if (rc != SQLITE_OK && rc != SQLITE_DONE && rc != SQLITE_ROW) fail(db, what);
}

}  // namespace

SqliteWriter::SqliteWriter(const std::string& path) {
  if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr) !=
      SQLITE_OK) {
    const std::string msg = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw RecordingError("cannot create recording '" + path + "': " + msg);
  }
  // one writer, crash-tolerant enough for a recorder: WAL, no fsync per transaction
  exec("PRAGMA journal_mode=WAL");
  exec("PRAGMA synchronous=NORMAL");
  exec("CREATE TABLE meta(key TEXT PRIMARY KEY, value TEXT NOT NULL)");
  exec(
      "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT UNIQUE NOT NULL, "
      "type_name TEXT NOT NULL, qos TEXT NOT NULL)");
  exec(
      "CREATE TABLE samples(topic_id INTEGER NOT NULL, receive_ns INTEGER NOT NULL, "
      "source_ns INTEGER NOT NULL, writer_guid BLOB, writer_seq INTEGER, codec INTEGER NOT NULL, "
      "raw_size INTEGER NOT NULL, data BLOB NOT NULL, crc32 INTEGER)");
  exec("CREATE INDEX samples_by_time ON samples(receive_ns)");
  set_meta("format", kFormat);
  check(db_,
        sqlite3_prepare_v2(db_,
                           "INSERT INTO samples(topic_id, receive_ns, source_ns, writer_guid, "
                           "writer_seq, codec, raw_size, data, crc32) VALUES(?,?,?,?,?,?,?,?,?)",
                           -1, &insert_, nullptr),
        "prepare insert");
}

SqliteWriter::~SqliteWriter() { close(); }

void SqliteWriter::close() {
  if (!db_) return;
  sqlite3_finalize(insert_);
  insert_ = nullptr;
  sqlite3_exec(db_, "PRAGMA wal_checkpoint(TRUNCATE)", nullptr, nullptr, nullptr);
  sqlite3_close(db_);
  db_ = nullptr;
}

void SqliteWriter::exec(const std::string& sql) {
  char* err = nullptr;
  if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &err) != SQLITE_OK) {
    const std::string msg = err ? err : "?";
    sqlite3_free(err);
    throw RecordingError("sqlite: " + sql + ": " + msg);
  }
}

int SqliteWriter::add_topic(const std::string& name, const std::string& type_name,
                            const std::string& qos, const std::string& /*schema*/) {
  sqlite3_stmt* st = nullptr;
  check(db_,
        sqlite3_prepare_v2(db_, "INSERT INTO topics(name, type_name, qos) VALUES(?,?,?)", -1, &st,
                           nullptr),
        "prepare topic");
  sqlite3_bind_text(st, 1, name.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(st, 2, type_name.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(st, 3, qos.c_str(), -1, SQLITE_TRANSIENT);
  const int rc = sqlite3_step(st);
  sqlite3_finalize(st);
  check(db_, rc, "insert topic " + name);
  return static_cast<int>(sqlite3_last_insert_rowid(db_));
}

void SqliteWriter::set_meta(const std::string& key, const std::string& value) {
  sqlite3_stmt* st = nullptr;
  check(db_,
        sqlite3_prepare_v2(db_, "INSERT OR REPLACE INTO meta(key, value) VALUES(?,?)", -1, &st,
                           nullptr),
        "prepare meta");
  sqlite3_bind_text(st, 1, key.c_str(), -1, SQLITE_TRANSIENT);
  sqlite3_bind_text(st, 2, value.c_str(), -1, SQLITE_TRANSIENT);
  const int rc = sqlite3_step(st);
  sqlite3_finalize(st);
  check(db_, rc, "insert meta " + key);
}

void SqliteWriter::append(const std::vector<RecordedSample>& samples) {
  if (samples.empty()) return;
  std::uint64_t raw = 0, stored = 0;
  exec("BEGIN");
  for (const auto& s : samples) {
    const std::uint8_t* data = s.payload.data();
    std::size_t size = s.payload.size();
    int codec = kCodecRaw;
    if (size >= kCompressFrom) {
      zbuf_.resize(ZSTD_compressBound(size));
      const std::size_t z = ZSTD_compress(zbuf_.data(), zbuf_.size(), data, size, 1);
      if (!ZSTD_isError(z) && z < size) {
        data = zbuf_.data();
        size = z;
        codec = kCodecZstd;
      }
    }
    sqlite3_bind_int(insert_, 1, s.topic_id);
    sqlite3_bind_int64(insert_, 2, s.receive_ns);
    sqlite3_bind_int64(insert_, 3, s.source_ns);
    sqlite3_bind_blob(insert_, 4, s.writer_guid, 16, SQLITE_STATIC);
    sqlite3_bind_int64(insert_, 5, s.writer_seq);
    sqlite3_bind_int(insert_, 6, codec);
    sqlite3_bind_int64(insert_, 7, static_cast<sqlite3_int64>(s.payload.size()));
    sqlite3_bind_blob(insert_, 8, data, static_cast<int>(size), SQLITE_STATIC);
    sqlite3_bind_int64(insert_, 9, crc32(s.payload.data(), s.payload.size()));
    const int rc = sqlite3_step(insert_);
    sqlite3_reset(insert_);
    if (rc != SQLITE_DONE) {
      sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
      fail(db_, "insert sample");
    }
    raw += s.payload.size();
    stored += size;
  }
  exec("COMMIT");
  raw_bytes_ += raw;  // only what was committed
  committed_ += samples.size();
  stored_bytes_ += stored;
}

SqliteReader::SqliteReader(const std::string& path) : path_(path) {
  if (sqlite3_open_v2(path.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    const std::string msg = db_ ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw RecordingError("cannot open recording '" + path + "': " + msg);
  }
  const auto m = meta();
  const auto f = m.find("format");
  if (f == m.end() || f->second != kFormat) {
    sqlite3_close(db_);
    db_ = nullptr;
    throw RecordingError("'" + path + "' is not a teleop recording (" + kFormat + ")");
  }
  sqlite3_stmt* st = nullptr;
  // files written without the per-sample CRC column are read unchecked (health() says so)
  if (sqlite3_prepare_v2(db_, "SELECT crc32 FROM samples LIMIT 0", -1, &st, nullptr) == SQLITE_OK) {
    has_crc_ = true;
  }
  sqlite3_finalize(st);
  st = nullptr;
  check(db_,
        sqlite3_prepare_v2(db_, "SELECT id, name, type_name, qos FROM topics ORDER BY id", -1, &st,
                           nullptr),
        "read topics");
  while (sqlite3_step(st) == SQLITE_ROW) {
    TopicRecord t;
    t.id = sqlite3_column_int(st, 0);
    t.name = reinterpret_cast<const char*>(sqlite3_column_text(st, 1));
    t.type_name = reinterpret_cast<const char*>(sqlite3_column_text(st, 2));
    t.qos = reinterpret_cast<const char*>(sqlite3_column_text(st, 3));
    topics_.push_back(t);
  }
  sqlite3_finalize(st);
  check(db_,
        sqlite3_prepare_v2(db_, "SELECT min(receive_ns), max(receive_ns) FROM samples", -1, &st,
                           nullptr),
        "read time range");
  if (sqlite3_step(st) == SQLITE_ROW) {
    first_ns_ = sqlite3_column_int64(st, 0);
    last_ns_ = sqlite3_column_int64(st, 1);
  }
  sqlite3_finalize(st);
  if (first_ns_ < 0 || last_ns_ < first_ns_ || last_ns_ - first_ns_ > kMaxRecordingSpanNs) {
    sqlite3_close(db_);
    db_ = nullptr;
    throw config::ConfigError(path + ": field 'samples.receive_ns': from " +
                              std::to_string(first_ns_) + " to " + std::to_string(last_ns_) +
                              " ns; receive times must be >= 0 and span at most " +
                              std::to_string(kMaxRecordingSpanNs / 1000000000) + " s");
  }
}

SqliteReader::~SqliteReader() {
  sqlite3_finalize(scan_);
  sqlite3_close(db_);
}

std::map<std::string, std::string> SqliteReader::meta() const {
  std::map<std::string, std::string> out;
  sqlite3_stmt* st = nullptr;
  if (sqlite3_prepare_v2(db_, "SELECT key, value FROM meta", -1, &st, nullptr) != SQLITE_OK) {
    return out;
  }
  while (sqlite3_step(st) == SQLITE_ROW) {
    out[reinterpret_cast<const char*>(sqlite3_column_text(st, 0))] =
        reinterpret_cast<const char*>(sqlite3_column_text(st, 1));
  }
  sqlite3_finalize(st);
  return out;
}

std::map<int, std::int64_t> SqliteReader::counts() const {
  std::map<int, std::int64_t> out;
  sqlite3_stmt* st = nullptr;
  check(db_,
        sqlite3_prepare_v2(db_, "SELECT topic_id, count(*) FROM samples GROUP BY topic_id", -1, &st,
                           nullptr),
        "count samples");
  while (sqlite3_step(st) == SQLITE_ROW) {
    out[sqlite3_column_int(st, 0)] = sqlite3_column_int64(st, 1);
  }
  sqlite3_finalize(st);
  return out;
}

void SqliteReader::scan(std::int64_t from_ns, std::int64_t to_ns,
                        const std::vector<int>& topic_ids) {
  sqlite3_finalize(scan_);
  scan_ = nullptr;
  std::string sql =
      std::string("SELECT topic_id, receive_ns, source_ns, writer_guid, writer_seq, codec, ") +
      "raw_size, data, " + (has_crc_ ? "crc32" : "NULL") + " FROM samples WHERE receive_ns >= ?1";
  if (to_ns > 0) sql += " AND receive_ns < ?2";
  if (!topic_ids.empty()) {
    sql += " AND topic_id IN (";
    for (std::size_t i = 0; i < topic_ids.size(); ++i) {
      sql += (i ? "," : "") + std::to_string(topic_ids[i]);
    }
    sql += ")";
  }
  sql += " ORDER BY receive_ns, rowid";
  check(db_, sqlite3_prepare_v2(db_, sql.c_str(), -1, &scan_, nullptr), "prepare scan");
  sqlite3_bind_int64(scan_, 1, from_ns);
  if (to_ns > 0) sqlite3_bind_int64(scan_, 2, to_ns);
}

bool SqliteReader::next(RecordedSample& out) {
  if (!scan_) return false;
  const int rc = sqlite3_step(scan_);
  if (rc == SQLITE_DONE) return false;
  if (rc != SQLITE_ROW) fail(db_, "scan samples");
  out.topic_id = sqlite3_column_int(scan_, 0);
  out.receive_ns = sqlite3_column_int64(scan_, 1);
  out.source_ns = sqlite3_column_int64(scan_, 2);
  std::memset(out.writer_guid, 0, 16);
  if (sqlite3_column_bytes(scan_, 3) == 16) {
    std::memcpy(out.writer_guid, sqlite3_column_blob(scan_, 3), 16);
  }
  out.writer_seq = sqlite3_column_int64(scan_, 4);
  const int codec = sqlite3_column_int(scan_, 5);
  const std::int64_t raw_size_field = sqlite3_column_int64(scan_, 6);
  const auto* blob = static_cast<const std::uint8_t*>(sqlite3_column_blob(scan_, 7));
  const auto n = static_cast<std::size_t>(sqlite3_column_bytes(scan_, 7));
  if (raw_size_field < 0 || raw_size_field > kMaxSampleBytes ||
      (codec == kCodecRaw && static_cast<std::size_t>(raw_size_field) != n)) {
    throw config::ConfigError(
        path_ + ": field 'samples.raw_size': " + std::to_string(raw_size_field) +
        " for a sample of " + std::to_string(n) + " stored bytes at receive_ns " +
        std::to_string(out.receive_ns) + "; allowed range [0, " + std::to_string(kMaxSampleBytes) +
        "], and equal to the stored size when uncompressed");
  }
  if (out.receive_ns < 0) {
    throw config::ConfigError(
        path_ + ": field 'samples.receive_ns': " + std::to_string(out.receive_ns) + " is negative");
  }
  const auto raw_size = static_cast<std::size_t>(raw_size_field);
  if (codec == kCodecZstd) {
    out.payload.resize(raw_size);
    const std::size_t got = ZSTD_decompress(out.payload.data(), raw_size, blob, n);
    if (ZSTD_isError(got) || got != raw_size) {
      throw RecordingError("corrupt compressed sample in the recording");
    }
  } else if (codec == kCodecRaw) {
    out.payload.assign(blob, blob + n);
  } else {
    throw RecordingError("unknown codec " + std::to_string(codec) + " in the recording");
  }
  check_crc(out);
  return true;
}

RecordingHealth SqliteReader::health() const {
  RecordingHealth h;
  h.how = has_crc_ ? "SQLite, a CRC-32 per sample"
                   : "SQLite without per-sample CRCs (payloads read unchecked)";
  return h;
}

void SqliteReader::check_crc(const RecordedSample& s) const {
  if (!has_crc_ || sqlite3_column_type(scan_, 8) == SQLITE_NULL) return;
  const std::int64_t want = sqlite3_column_int64(scan_, 8);
  const std::uint32_t got = crc32(s.payload.data(), s.payload.size());
  if (want == static_cast<std::int64_t>(got)) return;
  char text[96];
  std::snprintf(text, sizeof text, "%08llx recorded, %08x computed over its %zu payload bytes",
                static_cast<unsigned long long>(want), got, s.payload.size());
  throw config::ConfigError(path_ + ": field 'samples.crc32' of the sample at receive_ns " +
                            std::to_string(s.receive_ns) + " (topic id " +
                            std::to_string(s.topic_id) + "): " + text +
                            ": the payload is damaged; it must equal the CRC-32 of the payload");
}

std::string SqliteReader::verify_file() {
  sqlite3_stmt* st = nullptr;
  std::string result = "not checked";
  if (sqlite3_prepare_v2(db_, "PRAGMA quick_check", -1, &st, nullptr) == SQLITE_OK &&
      sqlite3_step(st) == SQLITE_ROW) {
    const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(st, 0));
    result = text ? text : "?";
  }
  sqlite3_finalize(st);
  if (result != "ok") {
    throw config::ConfigError(path_ + ": SQLite quick_check: " + result);
  }
  return result;
}

}  // namespace teleop::record
