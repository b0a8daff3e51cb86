#pragma once
// The master's DDS node: a fixed-rate haptic loop.
//
//   each cycle (1 kHz):  device.read -> controller.update (newest delayed SlaveState)
//                        -> safety.filter -> device.write -> forward delay channel
//                        -> MasterCommand writer;   SlaveState reader -> backward channel
//
// Before the operator's script starts, a homing phase brings the slave smoothly from where
// it is to the script's start (no force rendered); the cycle re-homes after a link loss, a
// server restart or a takeover (MasterCycle). One master owns the slave at a time
// (docs/topics.md, "Ownership"): a master refused by the server renders nothing and exits with
// status 4, or waits for the slave with wait_owner_s. At the end the force fades out at the
// device's rate bound and the master releases the slave. The round trip is measured on the master's
// own clock: SlaveState echoes the command's seq and send time, stamped when the command
// entered the forward channel, so it includes both injected delays.
#include <memory>
#include <string>

#include "client/control/bilateral_controller.hpp"
#include "client/control/safety.hpp"
#include "client/net/delay_config.hpp"
#include "common/dds/participant.hpp"
#include "common/util/realtime.hpp"

namespace teleop::master {

struct MasterOptions {
  dds::ParticipantOptions dds;
  double rate_hz = 1000.0;       ///< haptic loop rate [Hz]
  double command_rate_hz = 0.0;  ///< commands to the slave [Hz]; 0 = one per haptic cycle
  double duration_s = 0.0;       ///< stop after this long [s]; 0 = the script's length + 1 s
  std::uint64_t samples = 0;     ///< stop after this many haptic cycles (0 = no limit)
  double wait_server_s = 15.0;   ///< wait this long for the server before starting [s]
  double homing_s = 1.5;         ///< time to bring the slave to the script start [s]
  double state_rate_hz = 100.0;  ///< MasterState publication rate [Hz]
  double drain_s = 0.3;          ///< after the last command, keep reading this long [s]
  /// Another master owns the slave: wait up to this long for it to release it (or fall silent
  /// past the server's ownership watchdog) instead of exiting with status 4 [s]; 0 = no wait.
  double wait_owner_s = 0.0;
  /// TCP client profiles: with no answer from a server for this long, make a new participant
  /// (a new connection) and go on waiting [s]; 0 = never.
  double reconnect_s = 3.0;
  /// No valid device reading for this long: the slave holds and the force fades to zero at the
  /// device's rate bound until readings return (MasterCycle) [s], (0, 10].
  double driver_timeout_s = 0.1;
  RealtimeOptions realtime;  ///< scheduling of the haptic loop (common/util/realtime)
  std::string name;  ///< who this master is, in the server's ownership events ("" = identity)
  /// Apply live tuning requests from teleop/tuning (client/control/tuning.hpp); off: the
  /// master only publishes its tuning status, saying it does not accept any.
  bool accept_tuning = false;

  // device
  std::string device = "simulated";   ///< simulated | replay | external
  std::string replay_file;            ///< CSV for the replay device
  std::string script = "press-slip";  ///< operator script: hold|line|circle|step|press-slip
  double press_depth_m = 0.02;        ///< press-slip: intended depth below the surface [m]
  double tremor_m = 0.0;              ///< operator tremor amplitude [m]
  bool has_contact_point = false;     ///< contact_point_m given on the command line
  Eigen::Vector3d contact_point_m = Eigen::Vector3d::Zero();  ///< slave point of master origin

  ControllerParams controller;  ///< scheme, gains, workspace map
  DelayConfig forward;          ///< master -> slave injected channel
  DelayConfig backward;         ///< slave -> master injected channel
  SafetyParams safety;

  std::string log_csv;       ///< per-cycle CSV log (optional)
  std::string summary_json;  ///< JSON summary at exit (optional)
  bool quiet = false;
};

class MasterNode {
 public:
  explicit MasterNode(const MasterOptions& options);
  ~MasterNode();
  /// Runs the session. Returns the exit status (0 ok, 3 server never appeared, 4 refused: another
  /// master owns the slave).
  int run();

 private:
  struct Impl;
  MasterOptions impl_options_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace teleop::master
