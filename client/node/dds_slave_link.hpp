#pragma once
// DdsSlaveLink: the master cycle's link over DDS. send() hands a MasterCommand, stamped with its
// send time, to the command writer's network thread (dds::QueuedWriter: it never waits on the
// network; when the thread falls behind by the ring's length, the newest command replaces the
// unwritten one, counted);
// receive() takes the newest SlaveState from the reader's mailbox, and, as each state echoes the
// seq and send time of the newest command the server applied, measures the network round trip on
// the master's own clock (no synchronised clocks needed).
//
// Ownership (docs/topics.md): every command carries this master's session id and name; each
// SlaveState says whose session owns the slave and how many of the owner's commands the server
// received since it took the slave. The link counts this master's received commands from those
// figures, per ownership period and across server restarts (a restart is seen as the state's
// step counter going back; the samples of a new server life carry a new slave_epoch).
#include <algorithm>
#include <cstdint>
#include <limits>
#include <string>

#include "client/cycle/slave_link.hpp"
#include "client/node/rtt.hpp"
#include "client/node/server_health.hpp"
#include "common/dds/async_writer.hpp"
#include "common/dds/endpoint.hpp"
#include "common/dds/teleop_idl.hpp"
#include "common/util/clock.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::master {

/// A SlaveState with the master-clock time it was received.
struct ReceivedState {
  SlaveState state;
  std::int64_t receive_ns = 0;
};

class DdsSlaveLink final : public SlaveLink {
 public:
  /// What SlaveState says of this master's ownership of the slave.
  enum class Owner : std::uint8_t {
    kUnknown = 0,  ///< no owner reported, or ours not yet confirmed
    kMine = 1,     ///< this master's session owns the slave
    kOther = 2,    ///< another master's session owns it now
  };

  /// `master_session`: this master's session id (not 0); `master_name`: for the server's events.
  /// The command writer: a ring of kCommandRing commands (16 ms at 1 kHz: the most queueing
  /// delay the hand-off adds), then the newest.
  static constexpr std::size_t kCommandRing = 16;
  using CommandWriter = dds::QueuedWriter<MasterCommandPubSubType, kCommandRing>;

  DdsSlaveLink(CommandWriter& writer, dds::Mailbox<ReceivedState>& mailbox,
               std::uint32_t master_session = 1, const std::string& master_name = "")
      : writer_(writer), mailbox_(mailbox), rtt_(1 << 20), session_(master_session) {
    message_.master_session(master_session);
    message_.master_name(master_name.substr(0, 48));
    writer_.prime(message_);  // the hand-off buffers get the name's capacity now, not in the loop
  }

  /// Takes the newest state already waiting (before the session starts): the baseline of the
  /// server's command count.
  bool take_newest() {
    if (!mailbox_.take_if_newer(rx_, seen_)) return false;
    count_received();
    return true;
  }

  void send(const SlaveCommand& command) override {
    // send time = hand-off time: the echo gives the network round trip
    to_idl(command, now_ns(), message_);
    if (!writer_.write(message_)) return;
    if (command.release) {
      ++releases_sent_;  // not a command of the session: not in sent()
    } else {
      ++sent_;
    }
    newest_sent_seq_ = std::max(newest_sent_seq_, command.seq);
  }

  bool receive(double now_s, SlaveSample& sample, double& at_s) override {
    if (!take_echo()) return false;
    sample = from_idl(rx_.state);
    sample.slave_epoch = static_cast<std::uint32_t>(restarts_);
    at_s = now_s;
    return sample.valid;
  }

  /// After the loop: keeps measuring late echoes (and the server's receive count).
  void drain() { take_echo(); }

  /// The newest SlaveState received (raw).
  const SlaveState& newest_state() const { return rx_.state; }
  std::uint64_t sent() const { return sent_; }
  const RttTracker& rtt() const { return rtt_; }
  /// Round trip of the newest new echo [ms] (NaN before the first).
  double last_rtt_ms() const { return last_rtt_ms_; }
  /// Commands of this master the server received as the slave's owner, over every period of
  /// ownership and across server restarts.
  std::uint64_t received_in_session() const { return received_total_ + received_period_; }
  /// Seq of this master's first command as owner (0: it never owned the slave).
  std::uint64_t first_owned_seq() const { return first_owned_seq_; }
  /// Ownership as the newest SlaveState reports it, and the other owner's session.
  Owner owner() const { return owner_; }
  std::uint32_t other_owner_session() const { return other_session_; }
  std::uint32_t session() const { return session_; }
  /// Release commands written (the last commands of a session; not in sent()).
  std::uint64_t releases_sent() const { return releases_sent_; }
  /// Server restarts seen on SlaveState (its step counter went back).
  std::uint64_t restarts() const { return restarts_; }

 private:
  bool take_echo() {
    if (!mailbox_.take_if_newer(rx_, seen_)) return false;
    const double r = rtt_.on_echo(rx_.state.command_seq(), rx_.state.command_send_time_ns(),
                                  rx_.receive_ns, newest_sent_seq_);
    if (r >= 0) last_rtt_ms_ = r;
    count_received();
    return true;
  }

  void count_received() {
    const SlaveState& st = rx_.state;
    const bool restarted = any_state_ && st.seq() < last_state_seq_;
    if (restarted) ++restarts_;
    last_state_seq_ = st.seq();
    any_state_ = true;
    if (st.owner_session() == session_ && st.owner_session() != 0) {
      owner_ = st.owner_active() ? Owner::kMine : Owner::kUnknown;
      // an ownership period is one server life and one take of the slave
      if (!in_period_ || restarts_ != period_epoch_ || st.owner_first_seq() != period_first_seq_) {
        received_total_ += received_period_;
        received_period_ = 0;
        in_period_ = true;
        period_epoch_ = restarts_;
        period_first_seq_ = st.owner_first_seq();
        if (first_owned_seq_ == 0) first_owned_seq_ = st.owner_first_seq();
      }
      received_period_ = std::max(received_period_, st.owner_commands_received());
    } else if (st.owner_active() && st.owner_session() != 0) {
      owner_ = Owner::kOther;
      other_session_ = st.owner_session();
    } else {
      owner_ = Owner::kUnknown;
    }
  }

  CommandWriter& writer_;
  dds::Mailbox<ReceivedState>& mailbox_;
  RttTracker rtt_;
  ReceivedState rx_;
  std::uint64_t seen_ = 0;
  MasterCommand message_;
  std::uint64_t sent_ = 0;
  std::uint64_t newest_sent_seq_ = 0;
  double last_rtt_ms_ = std::numeric_limits<double>::quiet_NaN();
  std::uint32_t session_;
  Owner owner_ = Owner::kUnknown;
  std::uint32_t other_session_ = 0;
  std::uint64_t received_total_ = 0;   // closed ownership periods
  std::uint64_t received_period_ = 0;  // the current one
  bool in_period_ = false;
  std::uint64_t period_epoch_ = 0;
  std::uint64_t period_first_seq_ = 0;
  std::uint64_t first_owned_seq_ = 0;
  std::uint64_t releases_sent_ = 0;
  std::uint64_t last_state_seq_ = 0;
  std::uint64_t restarts_ = 0;
  bool any_state_ = false;
};

}  // namespace teleop::master
