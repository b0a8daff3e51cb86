#pragma once
// The bounded send queue of one bridge client (teleop_bridge). Frames are of two classes:
// kept frames (state, force, events, scene, stats: a queue in order, oldest dropped first when
// the bound is reached) and bulk frames (mesh vertex frames: at most one waiting per channel, a
// newer one replaces it). When the bound is reached bulk frames go first, then the oldest kept
// frames. Every drop is counted. The slots keep their capacity, so once warm, queuing a frame
// allocates nothing; the queue never holds more than `bound_bytes` of frames, and the capacity
// its slots keep stays under three times that (a slot emptied while they keep more than twice
// the bound gives its memory back).
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

namespace teleop::bridge {

enum class FrameClass { kKept, kBulk };

struct QueueCounts {
  std::uint64_t queued = 0;        ///< frames accepted
  std::uint64_t sent = 0;          ///< frames handed to the socket
  std::uint64_t dropped_bulk = 0;  ///< bulk frames dropped (replaced or pushed out)
  std::uint64_t dropped_kept = 0;  ///< kept frames dropped (the bound reached with no bulk left)
  std::uint64_t too_large = 0;     ///< frames larger than the whole bound (never queued)
};

class ClientQueue {
 public:
  /// `bound_bytes`: most frame bytes held; `bulk_channels`: channel slots of bulk frames;
  /// `kept_slots`: most kept frames held (a second bound, on their count).
  ClientQueue(std::size_t bound_bytes, std::size_t bulk_channels, std::size_t kept_slots = 4096);

  /// Queues a frame: `head` then `body` (the bridge's message header and the payload).
  /// `bulk_channel` indexes the bulk slot of a kBulk frame.
  void push(FrameClass cls, std::size_t bulk_channel, std::span<const std::uint8_t> head,
            std::span<const std::uint8_t> body);
  /// The next frame to send (kept frames first, then bulk), or nullptr when empty. Valid until
  /// pop() or push().
  const std::vector<std::uint8_t>* front() const;
  /// Removes the frame front() returned.
  void pop();
  bool empty() const { return kept_count_ == 0 && bulk_waiting_ == 0; }
  std::size_t bytes() const { return bytes_; }
  /// Memory the slots keep (their capacities) [bytes].
  std::size_t retained_bytes() const { return retained_; }
  std::size_t bound() const { return bound_; }
  const QueueCounts& counts() const { return counts_; }

 private:
  bool drop_one_bulk();
  void drop_oldest_kept();
  /// A slot just emptied: frees its memory when the slots keep more than twice the bound.
  void emptied(std::vector<std::uint8_t>& slot);
  std::size_t bound_;
  std::size_t bytes_ = 0;
  std::size_t retained_ = 0;
  std::vector<std::vector<std::uint8_t>> kept_;  // ring
  std::size_t kept_head_ = 0, kept_count_ = 0;
  std::vector<std::vector<std::uint8_t>> bulk_;  // one per bulk channel
  std::vector<bool> bulk_full_;
  std::size_t bulk_waiting_ = 0, bulk_next_ = 0;
  QueueCounts counts_;
};

}  // namespace teleop::bridge
