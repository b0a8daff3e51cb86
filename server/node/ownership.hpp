#pragma once
// Who commands the slave (docs/topics.md, "Ownership"). One master session owns the slave at a
// time:
//   - the first writer of a well-formed command takes it when nobody owns it;
//   - the owner keeps it while its commands arrive, and gives it up with an explicit release
//     (MasterCommand.release) or by falling silent for longer than the ownership watchdog
//     (`timeout_ns`), after which the next writer takes it over;
//   - commands of any other writer are refused: counted, never fed to the physics, and the first
//     refusal of each writer is reported with both names.
// The server's command reader calls admit() for every command that passed the field checks,
// before the owner's sequence and passivity checks. Allocation-free (fixed tables; the message
// of a notable decision is formatted into a fixed buffer). Not thread-safe: one reader thread.
#include <array>
#include <cstdint>

#include "common/sim/events.hpp"

namespace teleop::server {

/// A command writer: the DDS publication handle (16 bytes, the writer's GUID).
struct WriterId {
  std::array<std::uint8_t, 16> bytes{};
  bool operator==(const WriterId& o) const { return bytes == o.bytes; }
  bool operator!=(const WriterId& o) const { return !(*this == o); }
};

/// What admit() decided for one command.
enum class Admit : std::uint8_t {
  kOwner = 0,      ///< from the owner: goes on to the owner's checks and the physics
  kAcquired = 1,   ///< nobody owned the slave: this writer owns it now (goes on, like kOwner)
  kTakenOver = 2,  ///< the owner fell silent past the watchdog: this writer owns it now
  kReleased = 3,   ///< the owner gave the slave up with this command (not fed to the physics)
  kRefused = 4,    ///< another writer owns the slave: refused, counted
  kIgnored = 5,    ///< a release from a writer that does not own the slave: nothing to do
};
const char* to_string(Admit a);

class Ownership {
 public:
  /// `timeout_ns`: silence of the owner after which another writer may take the slave [ns].
  explicit Ownership(std::int64_t timeout_ns) : timeout_ns_(timeout_ns) {}

  /// One well-formed command from `writer` (its master session, name and seq) at server time
  /// `now_ns`. `release`: the command gives the slave up. See Admit.
  Admit admit(const WriterId& writer, std::uint32_t session, const char* name, std::uint64_t seq,
              bool release, std::int64_t now_ns);

  /// True if the last admit() made a decision worth an event (a new owner, a release, a takeover,
  /// the first refusal of a writer); message() then says it.
  bool notable() const { return notable_; }
  const char* message() const { return message_.data(); }
  /// Whom the notable decision is about: `session` the master that took, released, took over or
  /// was refused the slave; `other_session` the owner it was taken from or that holds it.
  const sim::EventTags& tags() const { return tags_; }

  /// Session of the owner, 0 when nobody owns the slave or the owner fell silent past the
  /// watchdog at `now_ns` (the slave is then free to take).
  std::uint32_t owner_session(std::int64_t now_ns) const;
  /// Session of the current owner, or of the last one after a release (0: never owned).
  std::uint32_t session() const { return session_; }
  /// True from a take until a release (the owner may have fallen silent: owner_session()).
  bool owned() const { return owned_; }
  /// When the owner's newest command arrived [ns].
  std::int64_t owner_last_ns() const { return last_ns_; }
  const char* owner_name() const { return owner_name_.data(); }
  /// Seq of the owner's first command as owner, and commands received from it since then.
  std::uint64_t owner_first_seq() const { return first_seq_; }
  std::uint64_t owner_received() const { return owner_received_; }
  /// Commands refused because another writer owned the slave.
  std::uint64_t refused() const { return refused_; }
  /// Owners the slave has had (acquisitions and takeovers).
  std::uint64_t changes() const { return changes_; }
  std::int64_t timeout_ns() const { return timeout_ns_; }

 private:
  void take(const WriterId& writer, std::uint32_t session, const char* name, std::uint64_t seq,
            std::int64_t now_ns);
  bool first_refusal_of(const WriterId& writer);

  std::int64_t timeout_ns_;
  bool owned_ = false;
  WriterId owner_;
  std::uint32_t session_ = 0;
  std::array<char, 49> owner_name_{};
  std::int64_t last_ns_ = 0;
  std::uint64_t first_seq_ = 0;
  std::uint64_t owner_received_ = 0;
  std::uint64_t refused_ = 0;
  std::uint64_t changes_ = 0;
  // writers refused so far (the newest 8): each is reported once
  std::array<WriterId, 8> refused_writers_{};
  std::size_t refused_count_ = 0;
  bool notable_ = false;
  std::array<char, 256> message_{};
  sim::EventTags tags_;
};

}  // namespace teleop::server
