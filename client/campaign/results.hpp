#pragma once
// One run of a campaign and its row of the results table.
//
// The row is the run's parameters followed by what the session measured (the figures of the
// session summary: verdict and its reason, stability, errors, transparency, energy, faults,
// channels; the groups the campaign's `measure:` names). Numbers are written in the shortest
// form that reads back to the same double (std::to_chars), "nan" where a figure was not
// measured and "inf" for an unbounded margin, so a row is the same bytes wherever it is made.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "client/campaign/campaign.hpp"

namespace teleop::campaign {

/// The header line of the results table (no newline).
std::string results_header(const Campaign& c);
/// The parameter cells of run `p` (the first columns of its row; no newline).
std::string parameter_cells(const Campaign& c, const RunParams& p);

/// What a run did at each master cycle (homing included), one row per cycle. The arrays are
/// sized before the session starts (reserve()), so recording a cycle allocates nothing; cycles
/// past the capacity are counted in `dropped`, not recorded.
struct RunTraces {
  /// The recorded channels: name and width (values per cycle). Vectors are in the slave
  /// (world) frame unless the name says otherwise.
  enum Channel : std::size_t {
    kTime,             ///< time_s: master clock [s]
    kHoming,           ///< homing: 1 while the master homes the slave (no metrics)
    kMasterPosition,   ///< master_position_m: the device mapped to the slave frame [m]
    kSlavePosition,    ///< slave_position_m: the slave's tip (ground truth) [m]
    kCommandPosition,  ///< command_position_m: the command the slave stepped with [m]
    kControllerForce,  ///< controller_force_n: the controller's force before safety [N]
    kDeviceForce,      ///< device_force_n: the force written to the device, device frame [N]
    kContactForce,     ///< contact_force_n: the environment's force on the tip (slave) [N]
    kContactAtMaster,  ///< contact_force_at_master_n: the same as the master has it [N]
    kPenetration,      ///< penetration_m: the tip's contact spring compression [m]
    kDeformation,      ///< deformation_m: indentation of the body touched [m]
    kInContact,        ///< in_contact: 1 when the tip touches something
    kSafetyScale,      ///< safety_scale: force scale of the safety layer [0, 1]
    kLinkOk,           ///< link_ok: 1 while slave samples arrive in time
    kChannelCount
  };
  static const char* name(std::size_t channel);
  static std::size_t width(std::size_t channel);

  std::size_t size = 0;      ///< cycles recorded
  std::size_t capacity = 0;  ///< cycles there is room for
  std::size_t dropped = 0;   ///< cycles not recorded (past the capacity)
  /// Per channel, capacity * width(channel) values, row-major; the first size rows are valid.
  std::vector<double> data[kChannelCount];

  /// Makes room for `cycles` cycles and clears what was recorded (allocates).
  void reserve(std::size_t cycles);
};

/// Runs `p` in-process on the simulated clock (client/sim/loopback_session.hpp with the
/// server's world as the slave) and returns its whole row (no newline). A run that throws
/// (a world that cannot be built) gives a row with verdict "error" and the message as reason.
/// With `traces`, each cycle is also recorded there (sized for the session first).
std::string run_one(const Campaign& c, const RunParams& p, RunTraces* traces = nullptr);

/// The run id as it names files and leads a row: the id zero-padded to 7 digits.
std::string run_name(std::size_t id);

}  // namespace teleop::campaign
