#pragma once
// Allocation-free event queue for the physics loop. Simulation code pushes events (contact
// begin/end, limits, faults); the server node drains them outside the step and publishes them
// on teleop/events. The kinds are checked against the EVENT_* constants of idl/Teleop.idl in
// common/dds/event_kinds.hpp.
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstring>

namespace teleop::sim {

enum class EventKind : std::uint8_t {
  kInfo = 0,
  kContactBegin = 1,
  kContactEnd = 2,
  kWatchdog = 3,
  kFault = 4,
  kModeChange = 5,
  kCommandRejected = 6,
  kLimit = 7,
  kSafety = 8,
  kOwnership = 9,  ///< a master took, released or was refused the slave
  kTuning = 10,    ///< a live tuning request was applied or rejected (teleop/tuning)
};

enum class Severity : std::uint8_t { kInfo = 0, kWarning = 1, kError = 2 };

/// What within its kind an event is about, for the events a program acts on (EVENT_SUBJECT_*).
enum class EventSubject : std::uint8_t {
  kNone = 0,
  kPositionGain = 1,  ///< kLimit: a command's K_ps was clamped to what the slave holds
};

/// Who and what an event is about: the fields a program matches instead of the message text.
struct EventTags {
  std::uint32_t session = 0;        ///< the master session it is about (0: none)
  std::uint32_t other_session = 0;  ///< ownership: the other master of the decision (0: none)
  EventSubject subject = EventSubject::kNone;
};

struct SimEvent {
  EventKind kind = EventKind::kInfo;
  Severity severity = Severity::kInfo;
  double value = 0.0;       ///< kind-specific number
  double sim_time_s = 0.0;  ///< when it happened [s]
  EventTags tags;
  char message[128] = {};
};

/// Fixed-capacity ring. push() never allocates; when full, the oldest event is dropped and
/// counted in dropped().
class EventQueue {
 public:
  static constexpr std::size_t kCapacity = 256;

  void push(EventKind kind, Severity severity, double sim_time_s, double value, const char* message,
            EventTags tags = {}) {
    SimEvent& e = ring_[(head_ + count_) % kCapacity];
    if (count_ == kCapacity) {
      head_ = (head_ + 1) % kCapacity;
      ++dropped_;
    } else {
      ++count_;
    }
    e.kind = kind;
    e.severity = severity;
    e.value = value;
    e.sim_time_s = sim_time_s;
    e.tags = tags;
    std::snprintf(e.message, sizeof(e.message), "%s", message);
  }

  /// Removes the oldest event into `out`; false when empty.
  bool pop(SimEvent& out) {
    if (count_ == 0) return false;
    out = ring_[head_];
    head_ = (head_ + 1) % kCapacity;
    --count_;
    return true;
  }

  std::size_t size() const { return count_; }
  std::uint64_t dropped() const { return dropped_; }
  void clear() { head_ = count_ = 0; }

 private:
  std::array<SimEvent, kCapacity> ring_{};
  std::size_t head_ = 0;
  std::size_t count_ = 0;
  std::uint64_t dropped_ = 0;
};

}  // namespace teleop::sim
