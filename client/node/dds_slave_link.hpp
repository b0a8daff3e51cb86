#pragma once
// DdsSlaveLink: the master cycle's link over DDS. send() writes a MasterCommand stamped with
// its DDS write time; receive() takes the newest SlaveState from the reader's mailbox, and, as
// each state echoes the seq and send time of the newest command the server applied, measures
// the network round trip on the master's own clock (no synchronised clocks needed).
#include <algorithm>
#include <cstdint>
#include <limits>

#include "client/cycle/slave_link.hpp"
#include "client/node/rtt.hpp"
#include "client/node/server_health.hpp"
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
  DdsSlaveLink(dds::Writer<MasterCommandPubSubType>& writer, dds::Mailbox<ReceivedState>& mailbox)
      : writer_(writer), mailbox_(mailbox), rtt_(1 << 20) {}

  /// Takes the newest state already waiting (before the session starts): the baseline of the
  /// server's command count.
  bool take_newest() {
    if (!mailbox_.take_if_newer(rx_, seen_)) return false;
    count_received();
    return true;
  }

  void send(const SlaveCommand& command) override {
    // send time = DDS write time: the echo gives the network round trip
    to_idl(command, now_ns(), message_);
    if (writer_.write(message_)) ++sent_;
    newest_sent_seq_ = std::max(newest_sent_seq_, command.seq);
  }

  bool receive(double now_s, SlaveSample& sample, double& at_s) override {
    if (!take_echo()) return false;
    sample = from_idl(rx_.state);
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
  /// Commands the server received during this session, across server restarts.
  std::uint64_t received_in_session() const { return received_.total(); }
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
    const bool restarted = any_state_ && rx_.state.seq() < last_state_seq_;
    if (restarted) ++restarts_;
    received_.feed(rx_.state.commands_received(), restarted);
    last_state_seq_ = rx_.state.seq();
    any_state_ = true;
  }

  dds::Writer<MasterCommandPubSubType>& writer_;
  dds::Mailbox<ReceivedState>& mailbox_;
  RttTracker rtt_;
  ReceivedState rx_;
  std::uint64_t seen_ = 0;
  MasterCommand message_;
  std::uint64_t sent_ = 0;
  std::uint64_t newest_sent_seq_ = 0;
  double last_rtt_ms_ = std::numeric_limits<double>::quiet_NaN();
  SessionCounter received_;
  std::uint64_t last_state_seq_ = 0;
  std::uint64_t restarts_ = 0;
  bool any_state_ = false;
};

}  // namespace teleop::master
