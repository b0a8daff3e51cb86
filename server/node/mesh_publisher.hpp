#pragma once
// Mesh frames at the visual rate from a thread of their own, through a double buffer: the
// physics loop copies node positions into the back buffer (never blocking: when the publisher
// is busy swapping the frame is skipped) and the publisher converts and writes them, so
// observers never slow the physics.
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

#include "common/dds/endpoint.hpp"
#include "server/world/world.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::server {

class MeshPublisher {
 public:
  /// Starts the thread when the scene has deformable bodies (none: offer() does nothing).
  /// `monitor_writer` (optional) gets every frame whose number is a multiple of
  /// round(visual rate / monitor_rate_hz): the monitors' rate-limited copy.
  MeshPublisher(const sim::WorldModel& model, const sim::WorldData& data,
                dds::Writer<MeshFramePubSubType>& writer,
                dds::Writer<MeshFramePubSubType>* monitor_writer = nullptr,
                double monitor_rate_hz = 10.0);
  ~MeshPublisher();
  MeshPublisher(const MeshPublisher&) = delete;
  MeshPublisher& operator=(const MeshPublisher&) = delete;

  /// Called from the physics loop: copies the bodies' positions into the back buffer (same
  /// sizes: no allocation) and wakes the publisher.
  void offer(const sim::WorldData& data, double sim_time_s);

 private:
  void run();

  const sim::WorldModel& model_;
  dds::Writer<MeshFramePubSubType>& writer_;
  dds::Writer<MeshFramePubSubType>* monitor_writer_;
  std::uint64_t monitor_every_ = 1;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::vector<Eigen::Matrix3Xd> back_, front_;  // same sizes from the start: no allocation
  bool pending_ = false;
  bool stop_ = false;
  std::uint64_t frame_no_ = 0;
  double time_s_ = 0.0;
  std::thread thread_;
};

}  // namespace teleop::server
