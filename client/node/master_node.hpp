#pragma once
// The master's DDS node: a fixed-rate haptic loop that reads the device, writes
// MasterCommand, reads the newest SlaveState, measures the round trip on its own clock
// (SlaveState echoes the command's seq and send time), renders the force and writes the
// device. When SlaveState stops arriving the rendered force fades to zero.
#include <memory>
#include <string>

#include "common/dds/participant.hpp"

namespace teleop::master {

struct MasterOptions {
  dds::ParticipantOptions dds;
  double rate_hz = 1000.0;        ///< haptic loop rate [Hz]
  double duration_s = 10.0;       ///< stop after this long [s] (0 = no limit)
  std::uint64_t samples = 0;      ///< stop after this many commands (0 = no limit)
  double wait_server_s = 15.0;    ///< wait this long for the server before starting [s]
  double link_timeout_s = 0.1;    ///< no SlaveState for this long: link lost [s]
  double force_fade_s = 0.05;     ///< force fades to zero over this time on link loss [s]
  double state_rate_hz = 100.0;   ///< MasterState publication rate [Hz]
  double drain_s = 0.3;           ///< after the last command, keep reading this long [s]
  std::string motion = "circle";  ///< scripted device motion: circle | press | hold
  double force_scale = 1.0;       ///< rendered force = force_scale * environment force
  double max_force_n = 10.0;      ///< device force saturation [N]
  std::string log_csv;            ///< per-cycle CSV log (optional)
  std::string summary_json;       ///< JSON summary at exit (optional)
  bool quiet = false;
};

class MasterNode {
 public:
  explicit MasterNode(const MasterOptions& options);
  ~MasterNode();
  /// Runs the session. Returns the exit status (0 ok, 3 server never appeared).
  int run();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace teleop::master
