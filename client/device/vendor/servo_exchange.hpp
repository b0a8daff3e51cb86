#pragma once
// Hand-off between a vendor SDK's servo thread (the 1 kHz callback that owns the hardware) and
// the master's haptic loop, with no locks on either side: each direction is a seqlock of one
// plain value. The servo callback publishes the newest reading and takes the newest force; the
// haptic loop does the opposite. Neither waits for the other; a reader retries only while a
// write is in progress (a few hundred nanoseconds).
#include <atomic>
#include <cstdint>
#include <type_traits>

namespace teleop::master::vendor {

template <class T>
class Seqlock {
  static_assert(std::is_trivially_copyable_v<T>, "Seqlock holds plain values");

 public:
  /// One writer only.
  void store(const T& v) {
    const std::uint32_t s = seq_.load(std::memory_order_relaxed);
    seq_.store(s + 1, std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_release);
    copy_in(v);
    std::atomic_thread_fence(std::memory_order_release);
    seq_.store(s + 2, std::memory_order_relaxed);
  }
  /// Any number of readers. Returns the number of stores so far (0: nothing stored yet).
  std::uint32_t load(T& out) const {
    while (true) {
      const std::uint32_t s1 = seq_.load(std::memory_order_acquire);
      if (s1 & 1u) continue;
      copy_out(out);
      std::atomic_thread_fence(std::memory_order_acquire);
      if (seq_.load(std::memory_order_relaxed) == s1) return s1 / 2;
    }
  }

 private:
  // word-wise atomic copies keep the race formally defined (and ThreadSanitizer quiet)
  static constexpr std::size_t kWords =
      (sizeof(T) + sizeof(std::uint64_t) - 1) / sizeof(std::uint64_t);
  void copy_in(const T& v) {
    std::uint64_t tmp[kWords] = {};
    __builtin_memcpy(tmp, &v, sizeof(T));
    for (std::size_t i = 0; i < kWords; ++i) words_[i].store(tmp[i], std::memory_order_relaxed);
  }
  void copy_out(T& out) const {
    std::uint64_t tmp[kWords];
    for (std::size_t i = 0; i < kWords; ++i) tmp[i] = words_[i].load(std::memory_order_relaxed);
    __builtin_memcpy(&out, tmp, sizeof(T));
  }
  std::atomic<std::uint32_t> seq_{0};
  std::atomic<std::uint64_t> words_[kWords] = {};
};

/// What the servo thread reads from the hardware, SI units, device frame.
struct ServoReading {
  double time_s = 0.0;
  double position_m[3] = {0, 0, 0};
  double velocity_mps[3] = {0, 0, 0};
  double orientation_wxyz[4] = {1, 0, 0, 0};
  std::uint32_t buttons = 0;
  bool fault = false;  ///< the SDK reported an error this tick
};

/// What the haptic loop asks the servo thread to render.
struct ServoCommand {
  double force_n[3] = {0, 0, 0};
  double torque_nm[3] = {0, 0, 0};
  bool enable = false;
};

struct ServoExchange {
  Seqlock<ServoReading> reading;
  Seqlock<ServoCommand> command;
};

}  // namespace teleop::master::vendor
