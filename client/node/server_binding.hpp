#pragma once
// ServerBinding: which server a master believes (docs/topics.md, "A master is bound to its
// server"). Any participant on the domain can write teleop/slave_state, teleop/server_stats and
// teleop/events; the master takes them only from one server, identified by the GUID prefix of
// the participant whose writers they come from (all of a server's writers share it).
//
//   - Before ownership is granted, the server is the participant whose SlaveState came first.
//   - The grant binds: the first SlaveState that names this master's session as the active owner
//     (the session token each command carries and the server echoes in every state) makes its
//     participant the bound server. A grant from another participant than the first seen, before
//     any binding, moves the binding there (two servers on one domain: the one that took this
//     master's commands).
//   - Once bound, samples from any other participant are ignored and counted by kind, unless the
//     bound server has been silent for `rebind_after_ns` and the other one grants this master the
//     slave (a restarted server is a new participant).
//
// The reader threads call accept_*(); counters and the description are read from any thread.
#include <array>
#include <atomic>
#include <cstdint>
#include <fastdds/rtps/common/GuidPrefix_t.hpp>
#include <mutex>
#include <string>

#include "common/dds/guid_text.hpp"

namespace teleop::master {

using dds::guid_prefix_text;

class ServerBinding {
 public:
  using Prefix = eprosima::fastrtps::rtps::GuidPrefix_t;
  enum Kind : std::uint8_t { kState = 0, kStats = 1, kEvent = 2, kKinds = 3 };

  ServerBinding(std::uint32_t master_session, std::int64_t rebind_after_ns)
      : session_(master_session), rebind_after_ns_(rebind_after_ns) {}

  /// A SlaveState from the participant `writer`: true when the master takes it.
  bool accept_state(const Prefix& writer, std::uint32_t owner_session, bool owner_active,
                    std::int64_t now_ns) {
    std::lock_guard<std::mutex> lock(mutex_);
    const bool grant = owner_active && owner_session != 0 && owner_session == session_;
    if (!has_server_) {
      server_ = writer;
      has_server_ = true;
    }
    if (writer == server_) {
      if (grant) bound_.store(true);
      last_state_ns_ = now_ns;
      return true;
    }
    if (grant && (!bound_.load() || now_ns - last_state_ns_ > rebind_after_ns_)) {
      if (bound_.load()) rebinds_.fetch_add(1);
      server_ = writer;
      bound_.store(true);
      last_state_ns_ = now_ns;
      return true;
    }
    note_foreign(kState, writer);
    return false;
  }

  /// ServerStats or a server Event from `writer`: true when it comes from the server. Samples
  /// that arrive before any server was seen are dropped uncounted (nothing to compare with yet).
  bool accept(Kind kind, const Prefix& writer) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!has_server_) return false;
    if (writer == server_) return true;
    note_foreign(kind, writer);
    return false;
  }

  /// Samples ignored because another participant wrote them, by kind, and in all.
  std::uint64_t foreign(Kind kind) const { return foreign_[kind].load(); }
  std::uint64_t foreign_total() const {
    return foreign_[kState].load() + foreign_[kStats].load() + foreign_[kEvent].load();
  }
  /// Whether the grant has bound the master to its server; times it moved to a new server.
  bool bound() const { return bound_.load(); }
  std::uint64_t rebinds() const { return rebinds_.load(); }
  /// The server's GUID prefix ("" before any), and the first other participant's.
  std::string server() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return has_server_ ? guid_prefix_text(server_) : std::string();
  }
  std::string first_foreign() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return has_foreign_ ? guid_prefix_text(foreign_prefix_) : std::string();
  }

 private:
  void note_foreign(Kind kind, const Prefix& writer) {
    foreign_[kind].fetch_add(1);
    if (!has_foreign_) {
      foreign_prefix_ = writer;
      has_foreign_ = true;
    }
  }

  const std::uint32_t session_;
  const std::int64_t rebind_after_ns_;
  mutable std::mutex mutex_;
  Prefix server_;
  bool has_server_ = false;
  Prefix foreign_prefix_;
  bool has_foreign_ = false;
  std::int64_t last_state_ns_ = 0;
  std::atomic<bool> bound_{false};
  std::atomic<std::uint64_t> rebinds_{0};
  std::array<std::atomic<std::uint64_t>, kKinds> foreign_{};
};

}  // namespace teleop::master
