#pragma once
// The server's physics period as an in-process slave (common/harness/in_process.hpp):
// the ServerCycle teleop_server runs (command watchdog, passivity port, world_step, contact
// estimate) and the SlaveSample the master would decode from its SlaveState, without DDS.
// LoopbackSession steps it for the delay sweep, the press scenarios and the master-side tests,
// so an in-process session and a networked one advance the same world by the same step.
//
//   WorldSlave slave(sim::tool_world_model(setup.slave, start), 1e-3);  // or a loaded model
//   LoopbackSession session(cfg, device, slave);                        // reset() at start()
//
// A command counts as arrived when its seq or send time differ from the last one's (or it is
// the first); the watchdog holds the slave when none arrives for command_timeout_s, as on the
// server. step() allocates nothing; reset() rebuilds the world (allocates).
#include <array>
#include <cstdint>
#include <optional>

#include "common/harness/in_process.hpp"
#include "server/node/server_cycle.hpp"
#include "server/node/slave_sample.hpp"

namespace teleop::server {

class WorldSlave final : public harness::InProcessSlave {
 public:
  /// `model` is copied; dt_s: the physics period [s]; command_timeout_s: the watchdog's
  /// timeout [s] (negative: the model's command_timeout_s, as the server uses). The world
  /// starts at the model's tool start until reset() moves it.
  explicit WorldSlave(sim::WorldModel model, double dt_s = 1e-3, double command_timeout_s = -1.0);
  WorldSlave(const WorldSlave&) = delete;  // the cycle refers to model_
  WorldSlave& operator=(const WorldSlave&) = delete;

  /// Rebuilds the world with the tool at rest at `position_m` (robot scenes: at home).
  void reset(const Eigen::Vector3d& position_m) override;
  void step(const SlaveCommand& command, double dt_s) override;
  const SlaveSample& sample() const override { return sample_; }
  /// The scene as the server publishes it, for this world now (server/node/scene_objects.hpp).
  SceneDescription describe_scene() const override;

  const sim::WorldModel& model() const { return model_; }
  const ServerCycle& cycle() const { return *cycle_; }
  /// The slave side of the passivity schemes.
  const passivity::SlavePassivityPort& port() const { return cycle_->port(); }
  /// Force of the slave's tracking controller in the last step [N].
  const Eigen::Vector3d& tracking_force_n() const { return cycle_->output().tracking_force_n; }
  std::uint64_t watchdog_trips() const override { return cycle_->watchdog_trips(); }
  /// Events the world and the watchdog raised since the last reset, by kind, and in all.
  std::uint64_t events_of(sim::EventKind kind) const override {
    return event_counts_[static_cast<std::size_t>(kind)];
  }
  std::uint64_t events_total() const { return events_total_; }

 private:
  sim::WorldModel model_;
  double dt_s_;
  double command_timeout_s_;
  std::optional<ServerCycle> cycle_;
  sim::EventQueue events_;
  SlaveSample sample_;
  std::int64_t now_ns_ = 0;  ///< the slave's clock: steps x dt [ns]
  std::uint64_t last_seq_ = 0;
  double last_send_time_s_ = 0.0;
  bool have_command_ = false;
  std::array<std::uint64_t, 256> event_counts_{};
  std::uint64_t events_total_ = 0;
};

}  // namespace teleop::server
