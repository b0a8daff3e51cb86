#include "common/record/recording.hpp"

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "common/config/config.hpp"
#include "common/record/mcap_format.hpp"
#include "common/record/mcap_recording.hpp"
#include "common/record/sqlite_recording.hpp"

namespace teleop::record {

namespace {

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

}  // namespace

const char* format_name(RecordingFormat format) {
  return format == RecordingFormat::kSqlite ? "sqlite" : "mcap";
}

RecordingFormat format_for_path(const std::string& path) {
  for (const char* ext : {".db", ".sqlite", ".sqlite3"}) {
    if (ends_with(path, ext)) return RecordingFormat::kSqlite;
  }
  return RecordingFormat::kMcap;
}

RecordingFormat parse_format(const std::string& flag, const std::string& text) {
  if (text == "mcap") return RecordingFormat::kMcap;
  if (text == "sqlite") return RecordingFormat::kSqlite;
  throw config::ConfigError("command line: " + flag + " '" + text +
                            "' is not a recording format (allowed: mcap, sqlite)");
}

std::optional<RecordingFormat> detect_format(const std::string& path) {
  char head[16] = {};
  std::ifstream in(path, std::ios::binary);
  if (!in.read(head, sizeof head)) {
    // an MCAP file is at least its magic and header; SQLite's header is 100 bytes
    return std::nullopt;
  }
  if (std::memcmp(head, mcap::kMagic, sizeof mcap::kMagic) == 0) return RecordingFormat::kMcap;
  if (std::memcmp(head, "SQLite format 3", 16) == 0) return RecordingFormat::kSqlite;
  return std::nullopt;
}

RecordingWriter::RecordingWriter(const std::string& path, RecordingFormat format,
                                 const McapOptions& mcap)
    : format_(format) {
  std::error_code ec;
  const auto st = std::filesystem::symlink_status(path, ec);
  if (path.empty()) throw config::ConfigError("the recording's file name is empty");
  if (!ec && std::filesystem::exists(st) && !std::filesystem::is_regular_file(st)) {
    throw config::ConfigError(path +
                              ": exists and is not a regular file; a recording replaces "
                              "only a regular file");
  }
  std::remove(path.c_str());
  if (format == RecordingFormat::kSqlite) {
    impl_ = std::make_unique<SqliteWriter>(path);
  } else {
    impl_ = std::make_unique<McapRecordingWriter>(path, mcap);
  }
}

RecordingWriter::RecordingWriter(const std::string& path)
    : RecordingWriter(path, format_for_path(path)) {}

RecordingWriter::~RecordingWriter() {
  try {
    close();
  } catch (...) {
  }
}

int RecordingWriter::add_topic(const std::string& name, const std::string& type_name,
                               const std::string& qos, const std::string& schema) {
  return impl_->add_topic(name, type_name, qos, schema);
}

void RecordingWriter::set_meta(const std::string& key, const std::string& value) {
  impl_->set_meta(key, value);
}

void RecordingWriter::append(const std::vector<RecordedSample>& samples) { impl_->append(samples); }

std::uint64_t RecordingWriter::raw_bytes() const { return impl_->raw_bytes(); }
std::uint64_t RecordingWriter::stored_bytes() const { return impl_->stored_bytes(); }
std::uint64_t RecordingWriter::samples_in_file() const { return impl_->samples_in_file(); }
void RecordingWriter::close() { impl_->close(); }

RecordingReader::RecordingReader(const std::string& path) : path_(path) {
  std::error_code exists_ec;
  if (!std::filesystem::exists(path, exists_ec)) {
    throw RecordingError("cannot open recording '" + path + "': no such file");
  }
  config::require_regular_file(path, "recording");
  const auto format = detect_format(path);
  if (!format) {
    throw RecordingError("'" + path +
                         "' is not a teleop recording (neither MCAP nor SQLite: its first bytes "
                         "are neither format's magic)");
  }
  format_ = *format;
  if (format_ == RecordingFormat::kSqlite) {
    impl_ = std::make_unique<SqliteReader>(path);
  } else {
    impl_ = std::make_unique<McapRecordingReader>(path);
  }
}

RecordingReader::~RecordingReader() = default;

const std::vector<TopicRecord>& RecordingReader::topics() const { return impl_->topics(); }
std::map<std::string, std::string> RecordingReader::meta() const { return impl_->meta(); }
std::map<int, std::int64_t> RecordingReader::counts() const { return impl_->counts(); }
std::int64_t RecordingReader::first_ns() const { return impl_->first_ns(); }
std::int64_t RecordingReader::last_ns() const { return impl_->last_ns(); }
RecordingHealth RecordingReader::health() const { return impl_->health(); }
std::string RecordingReader::verify_file() { return impl_->verify_file(); }

void RecordingReader::scan(std::int64_t from_ns, std::int64_t to_ns,
                           const std::vector<int>& topic_ids) {
  impl_->scan(from_ns, to_ns, topic_ids);
}

bool RecordingReader::next(RecordedSample& out) { return impl_->next(out); }

}  // namespace teleop::record
