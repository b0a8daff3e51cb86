#pragma once
// ExperimentPublisher: teleop/experiment (idl/Teleop.idl, ExperimentDescription), what a
// session is for every observer: scheme, gains in force, the injected impairment of each
// direction, the loop delay the controller lives with, the device and whether it is live.
// The topic is latched (reliable, transient local, keep last 1), so an observer that joins late
// gets the newest description at once. update() runs once per haptic cycle: it writes when a
// described value changes (a tuning ramp, a device falling silent or coming back) and otherwise
// once per period with the newest loop delay. It allocates nothing and never waits: the sample
// goes to a network thread (common/dds/async_writer.hpp).
#include <array>
#include <cstdint>
#include <string>

#include "client/cycle/master_cycle.hpp"
#include "common/dds/async_writer.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::master {

/// DEVICE_* constant of a --device value.
std::uint8_t device_kind(const std::string& device);

class ExperimentPublisher {
 public:
  /// Loop delays kept per period for the percentiles (more in one period are not kept).
  static constexpr std::size_t kWindow = 8192;

  ExperimentPublisher(dds::Participant& participant, double period_s = 1.0);

  /// Before the loop: the fields that do not change during a session.
  void begin(const MasterCycle& cycle, std::uint32_t master_session, const std::string& name,
             const std::string& device, double rate_hz);
  /// One loop delay measured this cycle [ms]. Real-time safe.
  void record_loop_delay(double ms);
  /// Writes the description when a described value changed or a period has passed since the
  /// last write. Returns true when it wrote. Real-time safe.
  bool update(const MasterCycle& cycle, double now_s, std::int64_t now_ns);

  const ExperimentDescription& last() const { return sample_; }
  std::uint64_t written() const { return writes_; }
  std::uint64_t failures() const { return writer_.failures(); }
  bool flush(double timeout_s) { return writer_.flush(timeout_s); }

 private:
  void fill(const MasterCycle& cycle, double now_s, ExperimentDescription& d) const;
  static bool same_setup(const ExperimentDescription& a, const ExperimentDescription& b);

  dds::LatestWriter<ExperimentDescriptionPubSubType> writer_;
  double period_s_;
  ExperimentDescription sample_;  // the newest written
  ExperimentDescription next_;    // scratch for this cycle
  std::array<double, kWindow> window_{};
  std::size_t window_n_ = 0;
  double last_write_s_ = -1.0;
  std::uint64_t writes_ = 0;
};

}  // namespace teleop::master
