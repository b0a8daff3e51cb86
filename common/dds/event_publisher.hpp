#pragma once
// The one writer of teleop/events: the server's and the master's events go out through it, each
// with its program's name as source, a sequence number, the writer's clock and the tags a
// program matches on (session, other_session, subject: sim::EventTags) instead of the text.
//
//   dds::EventPublisher events(participant, "server");
//   events.publish(sim_event);               // from a loop: a copy into a primed ring, no wait
//
// publish() is called from one thread at a time (the node's loop, or its start before the loop);
// it fills a scratch sample (the IDL's bounded strings are fixed arrays: a message past 256
// characters is cut) and hands it to a QueuedWriter: no allocation.
#include <cstdint>

#include "common/dds/async_writer.hpp"
#include "common/dds/topics.hpp"
#include "common/sim/events.hpp"
#include "common/util/clock.hpp"

namespace teleop::dds {

class EventPublisher {
 public:
  /// Events kept for the network thread; older unwritten ones are counted in dropped().
  static constexpr std::size_t kQueued = 128;
  /// Event.message's bound in idl/Teleop.idl [characters].
  static constexpr std::size_t kMessageBound = 256;

  EventPublisher(Participant& participant, const char* source)
      : writer_(participant, topics::kEvents) {
    scratch_.source() = source;
    writer_.prime(scratch_);
  }

  /// Writes `e` (its kind, severity, value, tags and message) stamped with the next sequence
  /// number and the steady clock.
  void publish(const sim::SimEvent& e) { publish(e.kind, e.severity, e.message, e.value, e.tags); }
  void publish(sim::EventKind kind, sim::Severity severity, const char* message, double value,
               const sim::EventTags& tags = {}) {
    scratch_.seq(++seq_);
    scratch_.time_ns(now_ns());
    scratch_.kind(static_cast<std::uint8_t>(kind));
    scratch_.severity(static_cast<std::uint8_t>(severity));
    scratch_.message() = message;  // cut at the IDL's bound (kMessageBound)
    scratch_.value(value);
    scratch_.session(tags.session);
    scratch_.other_session(tags.other_session);
    scratch_.subject(static_cast<std::uint8_t>(tags.subject));
    writer_.write(scratch_);
  }

  /// Outside the loop: waits until the queued events were written (or timeout_s).
  bool flush(double timeout_s) { return writer_.flush(timeout_s); }
  std::uint64_t dropped() const { return writer_.dropped(); }
  std::uint64_t failures() const { return writer_.failures(); }
  std::uint64_t published() const { return seq_; }

 private:
  QueuedWriter<EventPubSubType, kQueued> writer_;
  Event scratch_;
  std::uint64_t seq_ = 0;
};

}  // namespace teleop::dds
