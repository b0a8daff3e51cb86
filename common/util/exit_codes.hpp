#pragma once
// The exit statuses of every program (docs/exit_codes.md holds the same table).
//
//   0  done; a session judged stable
//   1  runtime failure: an output that could not be written, a DDS or system error
//   2  bad command line, configuration, input file or output path; nothing ran
//   3  nobody to talk to: no server found (teleop_master), nothing received (teleop_record)
//   4  refused: another master owns the slave (teleop_master)
//   5  session degraded: the link lost too many commands, its round trip exceeded the scheme's
//      tolerance, or the server rejected most commands (the loop itself stayed stable)
//   6  session oscillating
//   7  session out of spec (the device was driven beyond its continuous rating)
//   8  session unstable (a cut by the safety layer always makes it unstable)
namespace teleop::exit_code {

constexpr int kOk = 0;
constexpr int kFailure = 1;
constexpr int kUsage = 2;
constexpr int kNoPeer = 3;
constexpr int kRefused = 4;
constexpr int kDegraded = 5;
constexpr int kOscillating = 6;
constexpr int kOutOfSpec = 7;
constexpr int kUnstable = 8;

}  // namespace teleop::exit_code
