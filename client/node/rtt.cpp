#include "client/node/rtt.hpp"

namespace teleop::master {

double RttTracker::on_echo(std::uint64_t command_seq, std::int64_t command_send_time_ns,
                           std::int64_t now_ns, std::uint64_t newest_sent_seq) {
  if (command_seq == 0 || command_seq > newest_sent_seq) return -1.0;
  // the server echoes the newest command at every physics step: count each command once
  if (any_ && command_seq <= newest_seq_) return -1.0;
  any_ = true;
  newest_seq_ = command_seq;
  ++unique_;
  const double rtt = static_cast<double>(now_ns - command_send_time_ns) * 1e-6;
  rtt_ms_.record(rtt);
  return rtt;
}

}  // namespace teleop::master
