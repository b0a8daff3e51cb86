#include "client/record/info.hpp"

#include <cinttypes>
#include <cstdarg>
#include <cstdio>
#include <map>

#include "common/record/recording.hpp"

namespace teleop::record {

namespace {

/// Appends printf-style text to `out`.
__attribute__((format(printf, 2, 3))) void add(std::string& out, const char* fmt, ...) {
  char buf[512];
  va_list args;
  va_start(args, fmt);
  std::vsnprintf(buf, sizeof buf, fmt, args);
  va_end(args);
  out += buf;
}

}  // namespace

std::string recording_info(const std::string& path) {
  RecordingReader r(path);
  const RecordingHealth h = r.health();
  std::string out;
  add(out, "%s: %s\n", path.c_str(), h.how.c_str());
  const double span_s = static_cast<double>(r.last_ns() - r.first_ns()) * 1e-9;
  add(out, "  span       %.3f s (receive times %" PRId64 " to %" PRId64 " ns)\n", span_s,
      r.first_ns(), r.last_ns());
  // read every sample: chunk CRCs, decompression, sizes
  std::map<int, std::uint64_t> read;
  std::uint64_t total = 0, bytes = 0;
  r.scan(r.first_ns());
  RecordedSample s;
  while (r.next(s)) {
    ++read[s.topic_id];
    ++total;
    bytes += s.payload.size();
  }
  if (r.format() == RecordingFormat::kMcap) {
    add(out, "  chunks     %" PRIu64 "\n", h.chunks);
  }
  add(out, "  samples    %" PRIu64 " (%.1f MB of payload)\n", total,
      static_cast<double>(bytes) / 1e6);
  for (const TopicRecord& t : r.topics()) {
    add(out, "    %-28s %-26s %-16s %8" PRIu64 "\n", t.name.c_str(), t.type_name.c_str(),
        t.qos.c_str(), read[t.id]);
  }
  out += "  checked    every sample read; whole file: " + r.verify_file() + "\n";
  if (h.recovered) {
    add(out, "  recovered  %s\n", h.note.c_str());
    add(out,
        "  dropped    %" PRIu64 " bytes, %" PRIu64 " chunks (%" PRIu64 " messages seen in them)\n",
        h.dropped_bytes, h.dropped_chunks, h.dropped_messages);
  }
  if (h.skipped_messages > 0) {
    add(out, "  skipped    %" PRIu64 " messages outside chunks\n", h.skipped_messages);
  }
  const auto meta = r.meta();
  for (const char* key : {"domain", "profile", "started_unix_ns", "stopped_unix_ns"}) {
    const auto it = meta.find(key);
    if (it != meta.end()) add(out, "  %-10s %s\n", key, it->second.c_str());
  }
  return out;
}

}  // namespace teleop::record
