#include "server/node/mesh_publisher.hpp"

#include <cmath>

#include "common/dds/rate_limited_publisher.hpp"
#include "server/node/state_message.hpp"

namespace teleop::server {

MeshPublisher::MeshPublisher(const sim::WorldModel& model, const sim::WorldData& data,
                             dds::Writer<MeshFramePubSubType>& writer,
                             dds::Writer<MeshFramePubSubType>* monitor_writer,
                             double monitor_rate_hz)
    : model_(model), writer_(writer), monitor_writer_(monitor_writer) {
  if (monitor_rate_hz > 0.0 && model.visual_rate_hz > monitor_rate_hz) {
    monitor_every_ =
        static_cast<std::uint64_t>(std::llround(model.visual_rate_hz / monitor_rate_hz));
  }
  if (data.bodies.empty()) return;
  // the surface nodes only (a volumetric body's interior nodes follow them in state.x)
  for (std::size_t i = 0; i < data.bodies.size(); ++i) {
    back_.push_back(data.bodies[i].state.x.leftCols(model.bodies[i].body.node_count));
  }
  front_ = back_;
  thread_ = std::thread([this] { run(); });
}

MeshPublisher::~MeshPublisher() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void MeshPublisher::offer(const sim::WorldData& data, double sim_time_s) {
  if (!thread_.joinable()) return;
  std::unique_lock<std::mutex> lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock()) return;  // publisher busy swapping: skip this frame, never block
  for (std::size_t i = 0; i < back_.size(); ++i) {
    back_[i] = data.bodies[i].state.x.leftCols(back_[i].cols());  // same size: no allocation
  }
  ++frame_no_;
  time_s_ = sim_time_s;
  pending_ = true;
  lock.unlock();
  cv_.notify_one();
}

void MeshPublisher::run() {
  // observers' data: only the CPU the physics leaves (rate_limited_publisher.hpp)
  dds::lower_this_thread_priority(10);
  MeshFrame frame;
  std::uint64_t monitor_block = ~0ULL;
  while (true) {
    std::uint64_t no = 0;
    double t = 0.0;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      cv_.wait(lock, [this] { return pending_ || stop_; });
      if (stop_) return;
      std::swap(front_, back_);
      pending_ = false;
      no = frame_no_;
      t = time_s_;
    }
    // the monitors' copy: the first frame of each block of monitor_every_ frames that we see
    // (frames skipped under the try-lock do not make the monitors miss a block)
    const bool to_monitor = monitor_writer_ && no / monitor_every_ != monitor_block;
    if (to_monitor) monitor_block = no / monitor_every_;
    for (std::size_t i = 0; i < front_.size(); ++i) {
      pack_mesh_frame(model_.bodies[i].object_id, front_[i], no, t, frame);
      writer_.write(frame);
      if (to_monitor) monitor_writer_->write(frame);
    }
  }
}

}  // namespace teleop::server
