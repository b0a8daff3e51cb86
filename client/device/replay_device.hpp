#pragma once
// ReplayDevice: replays a recorded handle trajectory from CSV.
//
// File format: an optional header line, then rows `time_s,x,y,z[,qw,qx,qy,qz]` with strictly
// increasing time [s] and positions [m]. Position is interpolated linearly, orientation by
// slerp, velocity is the slope of the current segment. Forces written to it are recorded
// (last_force_n) but do not move the handle: a replay is an open-loop operator.
#include <string>
#include <vector>

#include "client/device/haptic_device.hpp"

namespace teleop::master {

/// One recorded sample.
struct ReplaySample {
  double time_s = 0.0;                                              ///< [s]
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();             ///< [m]
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< unit quaternion
};

/// Largest |coordinate| of a replayed position [m] (device frame; a haptic device's workspace is
/// well under a metre).
constexpr double kReplayMaxPositionM = 10.0;
/// Largest |component| of a replayed quaternion before it is normalised [-].
constexpr double kReplayMaxQuaternion = 1e3;
/// Largest |time_s| of a replay row [s] (about 11.6 days).
constexpr double kReplayMaxTimeS = 1e6;

/// Parses replay CSV text. `file` is used in messages. @throws config::ConfigError naming
/// file, line and column of the first bad field (not a finite number, or outside
/// +-kReplayMaxTimeS, +-kReplayMaxPositionM, +-kReplayMaxQuaternion).
std::vector<ReplaySample> parse_replay_csv(const std::string& text, const std::string& file);
/// Reads and parses a replay CSV file. @throws config::ConfigError.
std::vector<ReplaySample> load_replay_csv(const std::string& path);

/// Device that plays back a trajectory. See the file comment.
class ReplayDevice final : public HapticDevice {
 public:
  /// Replays `path` (loaded in configure()).
  ReplayDevice(std::string path, DeviceSpec spec = {}, bool loop = false);
  /// Replays samples already in memory (must be non-empty, strictly increasing time).
  ReplayDevice(std::vector<ReplaySample> samples, DeviceSpec spec = {}, bool loop = false);

  void configure() override;
  void activate() override;
  void deactivate() override;
  DeviceReading read() override;
  void write(const Eigen::Vector3d& force_n, const Eigen::Vector3d& torque_nm) override;
  void advance(double dt_s) override { time_s_ += dt_s; }
  const DeviceSpec& spec() const override { return spec_; }
  DeviceLifecycle state() const override { return state_; }

  /// Duration of the record [s].
  double duration_s() const;
  /// True once the replay passed its last sample (and does not loop).
  bool finished() const { return !loop_ && !samples_.empty() && time_s_ > duration_s(); }
  /// Last force written [N].
  const Eigen::Vector3d& last_force_n() const { return force_n_; }

 private:
  std::string path_;
  DeviceSpec spec_;
  bool loop_ = false;
  std::vector<ReplaySample> samples_;
  DeviceLifecycle state_ = DeviceLifecycle::kUnconfigured;
  double time_s_ = 0.0;
  std::size_t cursor_ = 0;  ///< segment index of the previous read (search starts here)
  Eigen::Vector3d force_n_ = Eigen::Vector3d::Zero();
};

}  // namespace teleop::master
