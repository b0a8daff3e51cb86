#include "server/node/world_slave.hpp"

#include <cmath>
#include <utility>

#include "server/node/scene_objects.hpp"

namespace teleop::server {

WorldSlave::WorldSlave(sim::WorldModel model, double dt_s, double command_timeout_s)
    : model_(std::move(model)),
      dt_s_(dt_s),
      command_timeout_s_(command_timeout_s < 0.0 ? model_.command_timeout_s : command_timeout_s) {
  reset(model_.tool_start_m);
}

void WorldSlave::reset(const Eigen::Vector3d& position_m) {
  model_.tool_start_m = position_m;
  cycle_.reset();
  cycle_.emplace(model_, dt_s_, command_timeout_s_);
  events_.clear();
  event_counts_.fill(0);
  events_total_ = 0;
  now_ns_ = 0;
  have_command_ = false;
  last_seq_ = 0;
  last_send_time_s_ = 0.0;
  const sim::WorldOutput& o = cycle_->output();
  sample_ = SlaveSample{};
  sample_.position_m = o.tip_position_m;
  sample_.orientation = o.tip_orientation;
  sample_.sim_time_s = o.sim_time_s;
  sample_.valid = true;
}

SceneDescription WorldSlave::describe_scene() const {
  return server::describe_scene(model_, cycle_->data(), model_.physics_rate_hz);
}

void WorldSlave::step(const SlaveCommand& cmd, double dt_s) {
  if (dt_s != dt_s_) {
    dt_s_ = dt_s;
    cycle_->set_period_s(dt_s);
  }
  // a new arrival resets the watchdog, as the server's reader does for each accepted command
  if (!have_command_ || cmd.seq != last_seq_ || cmd.send_time_s != last_send_time_s_) {
    cycle_->on_command(cmd, now_ns_, std::llround(cmd.send_time_s * 1e9));
    have_command_ = true;
    last_seq_ = cmd.seq;
    last_send_time_s_ = cmd.send_time_s;
  }
  cycle_->step(now_ns_, events_);
  now_ns_ += std::llround(dt_s * 1e9);
  sim::SimEvent e;
  while (events_.pop(e)) {
    ++event_counts_[static_cast<std::size_t>(e.kind)];
    ++events_total_;
  }

  slave_sample(*cycle_, sample_);  // what the master decodes from the server's SlaveState
}

}  // namespace teleop::server
