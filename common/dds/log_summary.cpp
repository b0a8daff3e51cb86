#include "common/dds/log_summary.hpp"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <fastdds/dds/log/Log.hpp>
#include <map>
#include <memory>
#include <mutex>

namespace teleop::dds {
namespace {

using eprosima::fastdds::dds::Log;

std::atomic<std::uint64_t> g_oversized{0};
std::atomic<std::uint64_t> g_entries{0};

const char* kind_name(Log::Kind k) {
  switch (k) {
    case Log::Kind::Error:
      return "Error";
    case Log::Kind::Warning:
      return "Warning";
    default:
      return "Info";
  }
}

/// Per kind of line: how many repeats are not yet reported, and when it was last printed.
struct Tally {
  std::string line;
  std::uint64_t unreported = 0;
  std::chrono::steady_clock::time_point printed;
};

class Summary {
 public:
  void consume(const Log::Entry& e) {
    g_entries.fetch_add(1, std::memory_order_relaxed);
    const std::string category = e.context.category ? e.context.category : "";
    if (is_oversized_sample_line(category, e.message)) {
      g_oversized.fetch_add(1, std::memory_order_relaxed);
    }
    const auto now = std::chrono::steady_clock::now();
    std::lock_guard<std::mutex> lock(mutex_);
    auto [it, fresh] = tallies_.try_emplace(log_kind(category, e.message));
    Tally& t = it->second;
    if (fresh) {
      t.line = "fastdds: [" + category + " " + kind_name(e.kind) + "] " + e.message;
      t.printed = now;
      std::fprintf(stderr, "%s\n", t.line.c_str());
      return;
    }
    ++t.unreported;
    if (std::chrono::duration<double>(now - t.printed).count() >= kRepeatReportS) {
      report(t, now);
    }
  }

  void flush() {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto now = std::chrono::steady_clock::now();
    for (auto& [kind, t] : tallies_) {
      if (t.unreported > 0) report(t, now);
    }
  }

 private:
  static void report(Tally& t, std::chrono::steady_clock::time_point now) {
    std::fprintf(stderr, "%s (repeated %llu times in the last %.0f s)\n", t.line.c_str(),
                 static_cast<unsigned long long>(t.unreported),
                 std::chrono::duration<double>(now - t.printed).count());
    t.unreported = 0;
    t.printed = now;
  }

  std::mutex mutex_;
  std::map<std::string, Tally> tallies_;
};

/// The one summary, never destroyed: Fast DDS's logging thread may hand it an entry while the
/// program's statics are being destroyed at exit (a function-local static would be gone by then).
Summary& summary() {
  static Summary* s = new Summary();  // intentionally never deleted
  return *s;
}

class SummaryConsumer : public eprosima::fastdds::dds::LogConsumer {
 public:
  void Consume(const Log::Entry& entry) override { summary().consume(entry); }
};

}  // namespace

std::string log_kind(const std::string& category, const std::string& message) {
  std::string kind = category + "|";
  kind.reserve(kind.size() + message.size());
  bool in_digits = false;
  for (const char c : message) {
    const bool digit = c >= '0' && c <= '9';
    if (digit && !in_digits) kind += '#';
    if (!digit) kind += c;
    in_digits = digit;
  }
  return kind;
}

bool is_oversized_sample_line(const std::string& category, const std::string& message) {
  return category == "RTPS_READER_HISTORY" &&
         message.find("is larger than the history payload size") != std::string::npos;
}

void install_log_summary() {
  static std::once_flag once;
  std::call_once(once, [] {
    Log::ClearConsumers();
    Log::RegisterConsumer(std::make_unique<SummaryConsumer>());
  });
}

std::uint64_t oversized_samples() { return g_oversized.load(std::memory_order_relaxed); }

std::uint64_t fastdds_log_entries() { return g_entries.load(std::memory_order_relaxed); }

void flush_log_summary() {
  Log::Flush();
  summary().flush();
}

}  // namespace teleop::dds
