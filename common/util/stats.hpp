#pragma once
// Sample statistics for latency and step-time reporting: medians and tails, never one run.
#include <cstddef>
#include <cstdint>
#include <vector>

namespace teleop {

/// Percentile (p in [0, 100]) of `values` by linear interpolation between order statistics.
/// Sorts a copy; returns NaN for an empty input. Not for hot loops.
double percentile(std::vector<double> values, double p);

/// Summary of a sample set.
struct Summary {
  std::size_t count = 0;
  double min = 0, p50 = 0, p90 = 0, p99 = 0, p999 = 0, max = 0, mean = 0, stddev = 0;
};
/// Summary of a copy of `values` (allocates: not for hot loops).
Summary summarize(const std::vector<double>& values);
/// Summary of `values`, sorting them in place: allocates nothing (for real-time threads).
Summary summarize_in_place(std::vector<double>& values);

/// Fixed-capacity sample recorder for real-time loops: record() never allocates; when full
/// it keeps the newest `capacity` samples (a ring). snapshot() copies out for reporting.
class SampleWindow {
 public:
  explicit SampleWindow(std::size_t capacity);
  void record(double v);
  void clear();
  std::size_t size() const { return full_ ? buf_.size() : next_; }
  std::size_t capacity() const { return buf_.size(); }
  std::uint64_t total_recorded() const { return total_; }
  /// Copies the held samples (oldest first). Allocates: call outside the hot loop.
  std::vector<double> snapshot() const;
  /// snapshot() into a caller-owned vector whose capacity is reused.
  void snapshot_into(std::vector<double>& out) const;

 private:
  std::vector<double> buf_;
  std::size_t next_ = 0;
  bool full_ = false;
  std::uint64_t total_ = 0;
};

}  // namespace teleop
