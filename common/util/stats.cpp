#include "common/util/stats.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace teleop {

namespace {
double sorted_percentile(const std::vector<double>& s, double p) {
  if (s.empty()) return std::numeric_limits<double>::quiet_NaN();
  const double pos = std::clamp(p, 0.0, 100.0) / 100.0 * static_cast<double>(s.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, s.size() - 1);
  const double frac = pos - static_cast<double>(lo);
  return s[lo] + (s[hi] - s[lo]) * frac;
}
}  // namespace

double percentile(std::vector<double> values, double p) {
  std::sort(values.begin(), values.end());
  return sorted_percentile(values, p);
}

Summary summarize(const std::vector<double>& values) {
  std::vector<double> v = values;
  return summarize_in_place(v);
}

Summary summarize_in_place(std::vector<double>& v) {
  Summary s;
  s.count = v.size();
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  s.min = v.front();
  s.max = v.back();
  s.p50 = sorted_percentile(v, 50);
  s.p90 = sorted_percentile(v, 90);
  s.p99 = sorted_percentile(v, 99);
  s.p999 = sorted_percentile(v, 99.9);
  s.mean = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
  double acc = 0;
  for (double x : v) acc += (x - s.mean) * (x - s.mean);
  s.stddev = std::sqrt(acc / static_cast<double>(v.size()));
  return s;
}

SampleWindow::SampleWindow(std::size_t capacity) : buf_(std::max<std::size_t>(capacity, 1)) {}

void SampleWindow::record(double v) {
  buf_[next_] = v;
  ++next_;
  ++total_;
  if (next_ == buf_.size()) {
    next_ = 0;
    full_ = true;
  }
}

void SampleWindow::clear() {
  next_ = 0;
  full_ = false;
}

std::vector<double> SampleWindow::snapshot() const {
  std::vector<double> out;
  snapshot_into(out);
  return out;
}

void SampleWindow::snapshot_into(std::vector<double>& out) const {
  out.clear();
  if (full_) {
    out.insert(out.end(), buf_.begin() + static_cast<std::ptrdiff_t>(next_), buf_.end());
  }
  out.insert(out.end(), buf_.begin(), buf_.begin() + static_cast<std::ptrdiff_t>(next_));
}

}  // namespace teleop
