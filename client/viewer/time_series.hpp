#pragma once
// A fixed-capacity time series for plots. Samples falling into the same bucket (bucket_s wide)
// are merged (min, max, last), and the newest `capacity` buckets are kept in a ring, so a
// 1 kHz stream costs the plot at most capacity points and add() never allocates.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace teleop::viewer {

class TimeSeries {
 public:
  struct Bucket {
    double t_s = 0.0;  ///< time of the bucket's first sample [s]
    float min = 0.0f;
    float max = 0.0f;
    float last = 0.0f;
  };

  TimeSeries() = default;
  TimeSeries(std::size_t capacity, double bucket_s) { reset(capacity, bucket_s); }

  /// Sets the capacity and bucket width and empties the series (allocates).
  void reset(std::size_t capacity, double bucket_s) {
    ring_.assign(std::max<std::size_t>(capacity, 2), Bucket{});
    bucket_s_ = bucket_s;
    clear();
  }
  void clear() {
    head_ = 0;
    count_ = 0;
  }

  /// Adds a sample at time t_s [s]; non-finite values are ignored. Never allocates.
  void add(double t_s, double value) {
    if (!std::isfinite(value) || !std::isfinite(t_s) || ring_.empty()) return;
    const auto v = static_cast<float>(value);
    if (count_ > 0) {
      Bucket& newest = ring_[index(count_ - 1)];
      if (t_s < newest.t_s + bucket_s_) {
        newest.min = std::min(newest.min, v);
        newest.max = std::max(newest.max, v);
        newest.last = v;
        return;
      }
    }
    if (count_ == ring_.size()) {  // full: drop the oldest
      head_ = (head_ + 1) % ring_.size();
      --count_;
    }
    ring_[index(count_)] = Bucket{t_s, v, v, v};
    ++count_;
  }

  std::size_t size() const { return count_; }
  bool empty() const { return count_ == 0; }
  /// Bucket i, 0 = oldest.
  const Bucket& operator[](std::size_t i) const { return ring_[index(i)]; }
  const Bucket& newest() const { return ring_[index(count_ - 1)]; }
  double bucket_s() const { return bucket_s_; }

  /// Copies another series; allocation-free when both have the same capacity.
  void copy_from(const TimeSeries& other) {
    ring_ = other.ring_;
    head_ = other.head_;
    count_ = other.count_;
    bucket_s_ = other.bucket_s_;
  }

 private:
  std::size_t index(std::size_t i) const { return (head_ + i) % ring_.size(); }

  std::vector<Bucket> ring_;
  std::size_t head_ = 0;
  std::size_t count_ = 0;
  double bucket_s_ = 0.01;
};

}  // namespace teleop::viewer
