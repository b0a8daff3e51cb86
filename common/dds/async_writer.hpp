#pragma once
// Writers whose write() never waits on the network, for the 1 kHz loops.
//
//   dds::LatestWriter<MasterCommandPubSubType> commands(participant, topics::kMasterCommand);
//   commands.prime(prototype);      // before the loop: sizes every buffer (no allocation later)
//   ... in the loop:  commands.write(command);   // a copy and an atomic exchange, never a wait
//
// A DataWriter's write() can block: over TCP when the connection's send buffer is full (a cut
// or congested link), for a reliable topic when its history is full of unacknowledged samples.
// These writers hand the sample to a network thread of their own, which does the DDS write; the
// loop only copies the sample into a preallocated buffer and wakes the thread (a futex wake when
// the thread sleeps, no lock).
//
//   LatestWriter: newest-value hand-off (a triple buffer). When the network thread falls behind,
//                 the newest sample replaces the one not yet written (counted: replaced()):
//                 for topics written at most once a cycle whose newest sample is all that
//                 matters to their readers (observers' states, the device's commands).
//   QueuedWriter: a single-producer ring of N samples, written in order, so that every sample
//                 goes out while the thread keeps up (several commands in one cycle, every
//                 physics step's state). When the ring is full (the thread blocked, or slower
//                 than the loop) samples go to an overflow slot where the newest replaces the
//                 unwritten one (counted: dropped()): the thread writes the ring's older samples,
//                 then the newest, and the queue never holds more than N samples of latency.
//
// One thread calls write() (the producer); the writer's own thread is the only consumer. A
// write that the middleware refuses is counted (failures()), never silently lost.
#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>

#include "common/dds/endpoint.hpp"

namespace teleop::dds {

/// Three buffers between one producer and one consumer that never wait for each other: the
/// producer fills back() and publishes it; the consumer takes the newest published buffer.
template <class T>
class TripleBuffer {
 public:
  /// Producer: the buffer to fill next.
  T& back() { return buffers_[back_]; }
  /// Producer: makes back() the newest; true if it replaced a buffer the consumer never took.
  bool publish() {
    const std::uint8_t old = middle_.exchange(back_ | kFresh, std::memory_order_acq_rel);
    back_ = old & kIndex;
    return (old & kFresh) != 0;
  }
  /// Consumer: the newest published buffer if one came since the last take, else nullptr.
  T* take() {
    if ((middle_.load(std::memory_order_acquire) & kFresh) == 0) return nullptr;
    const std::uint8_t old = middle_.exchange(front_, std::memory_order_acq_rel);
    front_ = old & kIndex;
    return &buffers_[front_];
  }
  /// Whether a published buffer waits for the consumer (either side may ask).
  bool pending() const { return (middle_.load(std::memory_order_acquire) & kFresh) != 0; }
  /// Before any publish(): copies `value` into all three buffers (gives them their capacity).
  void fill(const T& value) {
    for (T& b : buffers_) b = value;
  }

 private:
  static constexpr std::uint8_t kIndex = 3, kFresh = 4;
  std::array<T, 3> buffers_{};
  std::atomic<std::uint8_t> middle_{1};
  std::uint8_t back_ = 0;   // producer's
  std::uint8_t front_ = 2;  // consumer's
};

/// The network thread of an asynchronous writer: sleeps on a futex word until the producer
/// signals, then calls `drain` until stopped.
class NetworkThread {
 public:
  template <class Drain>
  void start(Drain drain) {
    thread_ = std::thread([this, drain] {
      std::uint32_t seen = 0;
      while (!stop_.load(std::memory_order_acquire)) {
        const std::uint32_t now = signal_.load(std::memory_order_acquire);
        if (now == seen) {
          signal_.wait(seen, std::memory_order_acquire);
          continue;
        }
        seen = now;
        drain();
      }
      drain();  // what was handed over before the stop
    });
  }
  /// Producer: wakes the thread (no lock, no wait; a system call only when it sleeps).
  void signal() {
    signal_.fetch_add(1, std::memory_order_acq_rel);
    signal_.notify_one();
  }
  void stop() {
    if (!thread_.joinable()) return;
    stop_.store(true, std::memory_order_release);
    signal();
    thread_.join();
  }

 private:
  std::atomic<std::uint32_t> signal_{0};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

/// Counters of an asynchronous writer (read from any thread).
struct AsyncWriterCounters {
  std::atomic<std::uint64_t> handed{0};     ///< samples write() accepted
  std::atomic<std::uint64_t> skipped{0};    ///< replaced (LatestWriter) or dropped (QueuedWriter)
  std::atomic<std::uint64_t> processed{0};  ///< written or refused by the network thread
  std::atomic<std::uint64_t> failures{0};   ///< DDS write() returned an error
};

/// Waits (outside any loop) until the network thread has handled every sample handed to it or
/// `timeout_s` passed; true when it has.
inline bool wait_until_flushed(const AsyncWriterCounters& c, double timeout_s) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  for (;;) {
    const std::uint64_t handed = c.handed.load(), skipped = c.skipped.load();
    if (c.processed.load() + skipped >= handed) return true;
    if (std::chrono::steady_clock::now() >= end) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

template <class PubSub>
class LatestWriter {
 public:
  using Sample = typename PubSub::type;

  LatestWriter(Participant& participant, const Topic<PubSub>& topic) : writer_(participant, topic) {
    thread_.start([this] { drain(); });
  }
  ~LatestWriter() { thread_.stop(); }
  LatestWriter(const LatestWriter&) = delete;
  LatestWriter& operator=(const LatestWriter&) = delete;

  /// Before the first write(): gives every buffer the capacity of `prototype` (its strings and
  /// sequences), so that later copies of samples no larger do not allocate.
  void prime(const Sample& prototype) { slot_.fill(prototype); }

  /// Hands the sample to the network thread; never waits. Always true: a sample the thread
  /// has not written yet is replaced (counted).
  bool write(const Sample& sample) {
    slot_.back() = sample;
    if (slot_.publish()) counters_.skipped.fetch_add(1, std::memory_order_relaxed);
    counters_.handed.fetch_add(1, std::memory_order_release);
    thread_.signal();
    return true;
  }

  /// Outside the loop: waits until everything handed over was written (or timeout_s).
  bool flush(double timeout_s) { return wait_until_flushed(counters_, timeout_s); }

  /// Matched readers now (asks the DataWriter: not from a loop, it may wait on the writer's
  /// mutex while a write is blocked).
  int matched() const { return writer_.matched(); }
  /// Matched readers as the network thread last saw them (-1 before its first write): for loops.
  int matched_cached() const { return matched_cache_.load(std::memory_order_relaxed); }
  std::uint64_t handed() const { return counters_.handed.load(); }
  /// Samples replaced by a newer one before the network thread could write them.
  std::uint64_t replaced() const { return counters_.skipped.load(); }
  /// Samples the middleware took.
  std::uint64_t written() const { return counters_.processed.load() - counters_.failures.load(); }
  std::uint64_t failures() const { return counters_.failures.load(); }

 private:
  void drain() {
    while (Sample* s = slot_.take()) {
      if (!writer_.write(*s)) counters_.failures.fetch_add(1, std::memory_order_relaxed);
      counters_.processed.fetch_add(1, std::memory_order_release);
    }
    matched_cache_.store(writer_.matched(), std::memory_order_relaxed);
  }

  Writer<PubSub> writer_;
  TripleBuffer<Sample> slot_;
  std::atomic<int> matched_cache_{-1};
  AsyncWriterCounters counters_;
  NetworkThread thread_;  // last: started after, stopped before everything it uses
};

template <class PubSub, std::size_t N>
class QueuedWriter {
  static_assert(N >= 2, "a ring of at least two samples");

 public:
  using Sample = typename PubSub::type;

  QueuedWriter(Participant& participant, const Topic<PubSub>& topic)
      : writer_(participant, topic), ring_(std::make_unique<std::array<Sample, N>>()) {
    thread_.start([this] { drain(); });
  }
  ~QueuedWriter() { thread_.stop(); }
  QueuedWriter(const QueuedWriter&) = delete;
  QueuedWriter& operator=(const QueuedWriter&) = delete;

  /// Before the first write(): gives every slot the capacity of `prototype`.
  void prime(const Sample& prototype) {
    for (Sample& s : *ring_) s = prototype;
    Stamped p;
    p.sample = prototype;
    overflow_.fill(p);
  }

  /// Hands the sample to the network thread; never waits. Into the ring, in order; when the
  /// ring is full (or the overflow slot still holds a sample), into the overflow slot, where the
  /// newest sample replaces one not yet written (counted: dropped()). So the thread writes every
  /// sample while it keeps up, and the newest one next when it falls behind. Always true.
  bool write(const Sample& sample) {
    const std::uint64_t stamp = ++stamp_;
    const std::uint64_t head = head_.load(std::memory_order_relaxed);
    if (!overflow_.pending() && head - tail_.load(std::memory_order_acquire) < N) {
      (*ring_)[head % N] = sample;
      stamps_[head % N] = stamp;
      head_.store(head + 1, std::memory_order_release);
    } else {
      Stamped& b = overflow_.back();
      b.stamp = stamp;
      b.sample = sample;
      if (overflow_.publish()) counters_.skipped.fetch_add(1, std::memory_order_relaxed);
    }
    counters_.handed.fetch_add(1, std::memory_order_release);
    thread_.signal();
    return true;
  }

  bool flush(double timeout_s) { return wait_until_flushed(counters_, timeout_s); }

  /// Matched readers now (asks the DataWriter: not from a loop).
  int matched() const { return writer_.matched(); }
  /// Matched readers as the network thread last saw them (-1 before its first write): for loops.
  int matched_cached() const { return matched_cache_.load(std::memory_order_relaxed); }
  std::uint64_t handed() const { return counters_.handed.load(); }
  /// Samples replaced by a newer one in the overflow slot before the thread could write them.
  std::uint64_t dropped() const { return counters_.skipped.load(); }
  /// Samples the middleware took.
  std::uint64_t written() const { return counters_.processed.load() - counters_.failures.load(); }
  std::uint64_t failures() const { return counters_.failures.load(); }

 private:
  struct Stamped {
    std::uint64_t stamp = 0;  // hand-off order
    Sample sample{};
  };

  void put(Sample& s) {
    if (!writer_.write(s)) counters_.failures.fetch_add(1, std::memory_order_relaxed);
    counters_.processed.fetch_add(1, std::memory_order_release);
  }

  /// In hand-off order: the ring's samples older than the overflow sample, the overflow sample,
  /// then the rest (the producer fills the ring again only once the overflow slot was taken).
  void drain() {
    std::uint64_t tail = tail_.load(std::memory_order_relaxed);
    for (;;) {
      Stamped* y = overflow_.take();
      while (tail != head_.load(std::memory_order_acquire) &&
             (y == nullptr || stamps_[tail % N] < y->stamp)) {
        put((*ring_)[tail % N]);
        ++tail;
        tail_.store(tail, std::memory_order_release);
      }
      if (y != nullptr) {
        put(y->sample);
        continue;
      }
      if (tail == head_.load(std::memory_order_acquire)) break;
    }
    matched_cache_.store(writer_.matched(), std::memory_order_relaxed);
  }

  Writer<PubSub> writer_;
  std::unique_ptr<std::array<Sample, N>> ring_;
  std::array<std::uint64_t, N> stamps_{};
  TripleBuffer<Stamped> overflow_;
  std::uint64_t stamp_ = 0;  // producer's
  std::atomic<int> matched_cache_{-1};
  std::atomic<std::uint64_t> head_{0};  // producer's
  std::atomic<std::uint64_t> tail_{0};  // consumer's
  AsyncWriterCounters counters_;
  NetworkThread thread_;  // last: started after, stopped before everything it uses
};

}  // namespace teleop::dds
