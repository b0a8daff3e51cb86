#pragma once
// DriveSession: teleop_viewer --drive. The viewer becomes the master's haptic device and its
// tuning tool, over the same topics a hardware driver and any tool use:
//   - a 1 kHz thread advances the HandDrive (mouse/keyboard target -> speed-limited handle) and
//     writes teleop/device_state (teleop_master --device external reads it);
//   - teleop/device_command brings back the force the master renders (shown as an arrow at the
//     master's hand and as a bar against the device's peak force);
//   - send_tuning() writes teleop/tuning; teleop/tuning_status brings the master's answer, the
//     values in force and their bounds (teleop_master --accept-tuning applies requests).
// The render thread calls the other methods (it is the DriveTarget that DriveInput and the input
// script move); everything shared is behind one mutex.
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "client/viewer/drive_input.hpp"
#include "client/viewer/hand_drive.hpp"
#include "common/dds/endpoint.hpp"
#include "teleop/idl/DevicePubSubTypes.h"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::viewer {

/// What the render thread shows.
struct DriveView {
  Eigen::Vector3d target_m = Eigen::Vector3d::Zero();    ///< device frame [m]
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  ///< handle, device frame [m]
  Eigen::Vector3d force_n = Eigen::Vector3d::Zero();     ///< newest force from the master [N]
  bool force_enabled = false;                            ///< the master enables force output
  double force_age_s = 1e9;                              ///< since the newest DeviceCommand [s]
  std::uint64_t states_written = 0;
  std::uint64_t commands_received = 0;
  double max_force_n = 0.0;  ///< largest |force| received [N]
  bool have_status = false;
  TuningStatus status;  ///< newest tuning status of a master
  std::uint64_t tunings_sent = 0;
};

class DriveSession : public DriveTarget {
 public:
  /// `peak_force_n`: the device's declared peak force (DeviceState.max_force_n; the bar's full
  /// scale). Starts the 1 kHz thread.
  DriveSession(dds::Participant& participant, const HandDriveParams& params, double peak_force_n);
  ~DriveSession() override;
  DriveSession(const DriveSession&) = delete;
  DriveSession& operator=(const DriveSession&) = delete;

  // input (render thread), forwarded to the HandDrive under the lock
  void grab(const Eigen::Vector3d& anchor_world_m, const Eigen::Vector3d& view_dir,
            const Eigen::Vector3d& ray_origin, const Eigen::Vector3d& ray_dir) override;
  void drag(const Eigen::Vector3d& ray_origin, const Eigen::Vector3d& ray_dir) override;
  void release() override;
  bool dragging() const override;
  void nudge(const Eigen::Vector3d& direction, double dt_s) override;

  /// Writes a tuning request (fields: TUNE_* bits; values in the request's units).
  void send_tuning(const TuningRequest& request) override;

  DriveView view() const;
  double peak_force_n() const { return peak_force_n_; }
  /// {"states_written":..,"commands_received":..,"max_force_n":..,"final_position_m":[..],
  ///  "tunings_sent":..,"status":{...}} for --drive-json.
  std::string summary_json() const;

 private:
  void run();

  double peak_force_n_;
  dds::Writer<DeviceStatePubSubType> state_writer_;
  dds::Writer<TuningRequestPubSubType> tuning_writer_;
  std::unique_ptr<dds::Reader<DeviceCommandPubSubType>> command_reader_;
  std::unique_ptr<dds::Reader<TuningStatusPubSubType>> status_reader_;
  mutable std::mutex mutex_;
  HandDrive drive_;
  DriveView view_;
  std::int64_t last_command_ns_ = 0;
  std::uint64_t tuning_seq_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace teleop::viewer
