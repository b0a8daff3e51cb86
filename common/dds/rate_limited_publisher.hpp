#pragma once
// Rate-limited copies of a hot topic, written from a thread of their own.
//
//   dds::RateLimitedPublisher<SlaveStatePubSubType> views(
//       participant, {{topics::kSlaveStateView, topics::kViewRateHz},
//                     {topics::kSlaveStateMonitor, topics::kMonitorRateHz}});
//   ... in the 1 kHz loop, after the full-rate write:
//   views.offer(state);
//
// offer() copies the sample into a slot under a try-lock (when the publisher thread holds the
// slot the sample is skipped, never waited for) and returns: no system call, no allocation once
// the sample's sequences have their size. The publisher thread wakes at each output's period
// and writes the newest offered sample to that output's topic if it has not written it yet. So
// the loop's cost does not depend on how many observers read the outputs: the DDS sends to
// every matched reader happen on this thread.
//
// An output with rate 0 writes every offered sample that the thread sees; such samples are
// offered with wake = true (a condition-variable notify: for slow topics such as 1 Hz stats).
//
// The thread lowers its own priority (`thread_nice`, default 10): on a machine the loop shares
// with other processes, sending to observers takes only the CPU the loop leaves. (On loopback
// the kernel delivers a datagram into each receiving socket in the sender's system call, so this
// thread pays for every observer's receive path too.)
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "common/dds/endpoint.hpp"

namespace teleop::dds {

/// Raises the calling thread's niceness by `nice` (Linux: a thread's own priority); 0 or a
/// refusal leaves it unchanged. Lowering needs no privilege.
inline void lower_this_thread_priority(int nice) {
  if (nice <= 0) return;
  const int tid = static_cast<int>(gettid());
  errno = 0;
  const int now = getpriority(PRIO_PROCESS, static_cast<id_t>(tid));
  if (errno != 0) return;
  setpriority(PRIO_PROCESS, static_cast<id_t>(tid), std::min(19, now + nice));
}

template <class PubSub>
class RateLimitedPublisher {
 public:
  using Sample = typename PubSub::type;

  /// One rate-limited topic (its QoS class is the topic table's).
  struct Output {
    Topic<PubSub> topic;
    double rate_hz = 0.0;  ///< [Hz], (0, 1e4]; 0: every offered sample (offer with wake)
  };

  RateLimitedPublisher(Participant& participant, const std::vector<Output>& outputs,
                       int thread_nice = 10)
      : thread_nice_(thread_nice) {
    for (const Output& o : outputs) {
      if (!(o.rate_hz >= 0.0 && o.rate_hz <= 1e4)) {
        throw DdsError(std::string("rate of ") + o.topic.name + " must be in [0, 1e4] Hz, got " +
                       std::to_string(o.rate_hz));
      }
      Out out;
      out.writer = std::make_unique<Writer<PubSub>>(participant, o.topic);
      out.period_ns = o.rate_hz > 0.0 ? static_cast<std::int64_t>(1e9 / o.rate_hz) : 0;
      outs_.push_back(std::move(out));
    }
    thread_ = std::thread([this] { run(); });
  }

  ~RateLimitedPublisher() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    cv_.notify_all();
    if (thread_.joinable()) thread_.join();
  }
  RateLimitedPublisher(const RateLimitedPublisher&) = delete;
  RateLimitedPublisher& operator=(const RateLimitedPublisher&) = delete;

  /// Hot thread: copies `sample` into the slot unless the publisher thread holds it (then the
  /// sample is skipped and counted). `wake`: notify the publisher (rate-0 outputs).
  void offer(const Sample& sample, bool wake = false) {
    std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock()) {
      skipped_.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    slot_ = sample;
    ++version_;
    if (wake) woken_ = true;
    lock.unlock();
    if (wake) cv_.notify_one();
  }

  std::size_t outputs() const { return outs_.size(); }
  /// Readers matched to output i right now.
  int matched(std::size_t i) const { return outs_.at(i).writer->matched(); }
  /// Samples written to output i so far (read after the publisher stopped, or approximately).
  std::uint64_t written(std::size_t i) const {
    return outs_.at(i).count.load(std::memory_order_relaxed);
  }
  /// Offers skipped because the publisher thread held the slot.
  std::uint64_t skipped() const { return skipped_.load(std::memory_order_relaxed); }

 private:
  struct Out {
    std::unique_ptr<Writer<PubSub>> writer;
    std::int64_t period_ns = 0;
    std::int64_t next_ns = 0;
    std::uint64_t last_version = 0;
    std::atomic<std::uint64_t> count{0};
    Out() = default;
    Out(Out&& o) noexcept
        : writer(std::move(o.writer)),
          period_ns(o.period_ns),
          next_ns(o.next_ns),
          last_version(o.last_version),
          count(o.count.load()) {}
  };

  static std::int64_t steady_ns() {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::steady_clock::now().time_since_epoch())
        .count();
  }

  void run() {
    lower_this_thread_priority(thread_nice_);
    Sample front;
    std::uint64_t front_version = 0;
    const std::int64_t start = steady_ns();
    for (Out& o : outs_) o.next_ns = start + o.period_ns;
    while (true) {
      std::int64_t deadline = INT64_MAX;
      for (const Out& o : outs_) {
        if (o.period_ns > 0) deadline = std::min(deadline, o.next_ns);
      }
      {
        std::unique_lock<std::mutex> lock(mutex_);
        const auto pred = [this] { return stop_ || woken_; };
        if (deadline == INT64_MAX) {
          cv_.wait(lock, pred);
        } else {
          cv_.wait_until(lock,
                         std::chrono::steady_clock::time_point(std::chrono::nanoseconds(deadline)),
                         pred);
        }
        if (stop_) return;
        woken_ = false;
        if (version_ != front_version) {
          front = slot_;
          front_version = version_;
        }
      }
      const std::int64_t now = steady_ns();
      for (Out& o : outs_) {
        if (o.period_ns > 0) {
          if (now < o.next_ns) continue;
          o.next_ns += o.period_ns;
          if (o.next_ns <= now) o.next_ns = now + o.period_ns;  // fell behind: no burst
        }
        if (front_version == 0 || front_version == o.last_version) continue;
        o.writer->write(front);
        o.last_version = front_version;
        o.count.fetch_add(1, std::memory_order_relaxed);
      }
    }
  }

  int thread_nice_ = 10;
  std::vector<Out> outs_;
  std::mutex mutex_;
  std::condition_variable cv_;
  Sample slot_{};
  std::uint64_t version_ = 0;
  bool woken_ = false;
  bool stop_ = false;
  std::atomic<std::uint64_t> skipped_{0};
  std::thread thread_;
};

}  // namespace teleop::dds
