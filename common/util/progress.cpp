#include "common/util/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <utility>

namespace teleop {

namespace {

constexpr double kRedrawPeriodS = 0.25;

std::atomic<ProgressMode> g_mode{ProgressMode::kAuto};

double steady_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

void copy_text(char* dst, std::size_t n, const char* src) {
  std::snprintf(dst, n, "%s", src ? src : "");
}

}  // namespace

void set_progress_mode(ProgressMode mode) { g_mode.store(mode); }
ProgressMode progress_mode() { return g_mode.load(); }

ProgressMode progress_mode_from(bool progress, bool no_progress, bool quiet) {
  if (no_progress || quiet) return ProgressMode::kOff;
  return progress ? ProgressMode::kOn : ProgressMode::kAuto;
}

bool progress_wanted(ProgressMode mode, bool is_terminal) {
  return mode == ProgressMode::kOn || (mode == ProgressMode::kAuto && is_terminal);
}

std::FILE* progress_stream() {
  return progress_wanted(progress_mode(), isatty(STDERR_FILENO) == 1) ? stderr : nullptr;
}

void format_duration(char* buf, std::size_t n, double s) {
  if (!std::isfinite(s) || s < 0.0 || s > 1e9) {
    std::snprintf(buf, n, "?");
    return;
  }
  const long t = std::lround(s);
  if (t < 60) {
    std::snprintf(buf, n, "%lds", t);
  } else if (t < 3600) {
    std::snprintf(buf, n, "%ldm%02lds", t / 60, t % 60);
  } else {
    const long m = std::lround(s / 60.0);
    std::snprintf(buf, n, "%ldh%02ldm", m / 60, m % 60);
  }
}

namespace {
/// Appends printf-style text at buf + len (n in all), truncating; len stays below n.
__attribute__((format(printf, 4, 5))) void append(char* buf, std::size_t n, std::size_t& len,
                                                  const char* fmt, ...) {
  if (len >= n) return;
  std::va_list args;
  va_start(args, fmt);
  const int w = std::vsnprintf(buf + len, n - len, fmt, args);
  va_end(args);
  if (w > 0) len = std::min(n - 1, len + static_cast<std::size_t>(w));
}
}  // namespace

std::size_t format_progress(char* buf, std::size_t n, const ProgressView& v) {
  if (n == 0) return 0;
  std::size_t len = 0;
  const char* sep = *v.unit ? " " : "";
  if (*v.label) append(buf, n, len, "%s: ", v.label);
  if (v.total > 0.0) {
    append(buf, n, len, "%.*f/%.*f%s%s (%.1f %%)", v.decimals, v.done, v.decimals, v.total, sep,
           v.unit, 100.0 * std::min(1.0, v.done / v.total));
  } else {
    append(buf, n, len, "%.*f%s%s", v.decimals, v.done, sep, v.unit);
  }
  const double rate = v.elapsed_s > 0.0 ? v.done / v.elapsed_s : 0.0;
  append(buf, n, len, ", %.*f %s/s", rate < 10.0 ? 2 : 1, rate, *v.unit ? v.unit : "steps");
  char d[32];
  if (v.final) {
    format_duration(d, sizeof(d), v.elapsed_s);
    append(buf, n, len, ", done in %s", d);
    return len;
  }
  format_duration(d, sizeof(d), v.elapsed_s);
  append(buf, n, len, ", %s elapsed", d);
  if (v.total > 0.0) {
    const double eta = rate > 0.0 ? std::max(0.0, v.total - v.done) / rate : -1.0;
    format_duration(d, sizeof(d), eta);
    append(buf, n, len, ", ETA %s", d);
  }
  return len;
}

Progress::Progress(const char* label, double total, const char* unit, int decimals)
    : Progress(progress_stream(), label, total, unit, decimals) {}

Progress::Progress(std::FILE* out, const char* label, double total, const char* unit, int decimals,
                   Clock clock)
    : out_(out), total_(total), decimals_(decimals), clock_(std::move(clock)) {
  if (!clock_) clock_ = steady_seconds;
  copy_text(label_, sizeof(label_), label);
  copy_text(unit_, sizeof(unit_), unit);
  t0_ = clock_();
  next_draw_s_.store(0.0);  // the first call draws: the line shows from the start
}

Progress::~Progress() { finish(); }

double Progress::elapsed_s() const { return clock_() - t0_; }

void Progress::add(double n) {
  done_.fetch_add(n);
  if (out_) draw_if_due();
}

void Progress::set(double done) {
  done_.store(done);
  if (out_) draw_if_due();
}

void Progress::poll() {
  if (out_) draw_if_due();
}

void Progress::draw_if_due() {
  if (elapsed_s() < next_draw_s_.load()) return;
  if (drawing_.test_and_set()) return;  // another thread is drawing
  const double now = elapsed_s();
  if (now >= next_draw_s_.load() && !finished_.load()) {
    next_draw_s_.store(now + kRedrawPeriodS);
    draw(false);
  }
  drawing_.clear();
}

void Progress::draw(bool final) {
  ProgressView v;
  v.label = label_;
  v.unit = unit_;
  v.done = done_.load();
  v.total = total_;
  v.elapsed_s = elapsed_s();
  v.decimals = decimals_;
  v.final = final;
  char line[256];
  const std::size_t len = format_progress(line, sizeof(line), v);
  // spaces over the end of a longer previous line
  const int pad = last_len_ > len ? static_cast<int>(last_len_ - len) : 0;
  std::fprintf(out_, "\r%s%*s%s", line, pad, "", final ? "\n" : "");
  std::fflush(out_);
  last_len_ = len;
}

void Progress::finish() {
  if (finished_.exchange(true) || !out_) return;
  while (drawing_.test_and_set()) {
  }
  draw(true);
  drawing_.clear();
}

}  // namespace teleop
