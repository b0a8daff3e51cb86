#pragma once
// What the server this master is bound to said about it on teleop/events during its session,
// read from the events' fields (Event.kind, subject, session, other_session), never from their
// text: the faults it reported, its newest word on this master's ownership, and a clamp of the
// K_ps the master's session asked for. The events reader feeds it (after the binding dropped other
// participants' events); the loop and the report read it. Thread-safe.
#include <atomic>
#include <cstdint>
#include <limits>
#include <mutex>
#include <string>

#include "teleop/idl/Teleop.h"

namespace teleop::master {

class ServerWord {
 public:
  explicit ServerWord(std::uint32_t master_session) : session_(master_session) {}

  /// The session begins at `t_ns`: faults and clamps from before (the event log's history of
  /// the server, kept for late joiners) are not the session's.
  void start_session(std::int64_t t_ns) { start_ns_.store(t_ns); }

  /// One event of the bound server's participant, received at `now_ns`. A master's event
  /// (source "master") is not the server's word and is ignored.
  void on_event(const Event& e, std::int64_t now_ns) {
    if (e.source() != "server") return;
    const bool in_session = now_ns >= start_ns_.load();
    if (e.kind() == EVENT_FAULT && in_session) faults_.fetch_add(1);
    if (e.kind() == EVENT_LIMIT && e.subject() == EVENT_SUBJECT_POSITION_GAIN &&
        e.session() == session_ && in_session) {
      std::lock_guard<std::mutex> lock(mutex_);
      gain_clamp_ = e.message().c_str();
    }
    // a decision about this master, or one that took the slave from it or refused another
    // master because it holds the slave
    if (e.kind() == EVENT_OWNERSHIP && (e.session() == session_ || e.other_session() == session_)) {
      std::lock_guard<std::mutex> lock(mutex_);
      ownership_ = e.message().c_str();
    }
  }

  /// Fault events since the session began.
  std::uint64_t faults() const { return faults_.load(); }
  /// The newest ownership event about this master ("" none).
  std::string ownership() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return ownership_;
  }
  /// The server's message that it clamped the session's K_ps ("" none).
  std::string gain_clamp() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return gain_clamp_;
  }

 private:
  const std::uint32_t session_;
  std::atomic<std::int64_t> start_ns_{std::numeric_limits<std::int64_t>::max()};
  std::atomic<std::uint64_t> faults_{0};
  mutable std::mutex mutex_;
  std::string ownership_;
  std::string gain_clamp_;
};

}  // namespace teleop::master
