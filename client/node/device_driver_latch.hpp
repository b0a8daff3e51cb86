#pragma once
// Which external driver the master believes on teleop/device_state: one driver at a time, so
// that a second driver (or a second driving viewer) cannot move the master's hand.
#include <fastdds/rtps/common/InstanceHandle.h>
#include <atomic>
#include <cstdint>
#include <mutex>

namespace teleop::master {

/// The first writer is the device until it has been silent for more than kSilentNs; samples of
/// any other writer meanwhile are refused and counted. Called from the reader's thread; ignored()
/// may be read from any thread.
class DeviceDriverLatch {
 public:
  using Writer = eprosima::fastrtps::rtps::InstanceHandle_t;
  /// Silence after which another writer may take over [ns].
  static constexpr std::int64_t kSilentNs = 100'000'000;

  /// A sample of `writer` received at `now_ns` [ns] (a steady clock, never 0). Returns true when
  /// it is the believed driver's (then the latch remembers the time), false when it is ignored.
  bool accept(const Writer& writer, std::int64_t now_ns) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (seen_ns_ == 0 || now_ns - seen_ns_ > kSilentNs) {
      driver_ = writer;
    } else if (writer != driver_) {
      ignored_.fetch_add(1);
      return false;
    }
    seen_ns_ = now_ns;
    return true;
  }
  /// Samples refused so far.
  std::uint64_t ignored() const { return ignored_.load(); }

 private:
  std::mutex mutex_;
  Writer driver_;
  std::int64_t seen_ns_ = 0;  // the believed driver's newest sample [ns]; 0 before the first
  std::atomic<std::uint64_t> ignored_{0};
};

}  // namespace teleop::master
