#pragma once
// One physics period of the server, without DDS: the command watchdog, the slave side of the
// passivity schemes and the world step, in that order. The server node feeds it the newest
// accepted command and packs its result into SlaveState (state_message.hpp); tests drive it
// with plain commands and a clock of their own.
//
//   cycle.on_command(cmd, receive_ns, sent_ns); // newest accepted command, when one arrives
//   cycle.step(t_ns, events);                  // watchdog -> port -> world_step
//
// Allocation-free after construction; deterministic for the same commands and clock.
#include <cstdint>

#include <vector>

#include "common/control/bilateral_types.hpp"
#include "common/control/contact_model.hpp"
#include "common/control/slave_port.hpp"
#include "server/world/world.hpp"

namespace teleop::server {

class ServerCycle {
 public:
  /// `model` must outlive the cycle. dt_s: physics period [s]; command_timeout_s: hold the
  /// slave when no valid command arrived for this long [s].
  ServerCycle(const sim::WorldModel& model, double dt_s, double command_timeout_s);

  /// The newest accepted command, when it arrived [ns, server clock] and its send stamp as
  /// written on the wire [ns, master clock] (echoed unchanged in SlaveState).
  void on_command(const SlaveCommand& c, std::int64_t receive_ns, std::int64_t send_time_ns);
  /// One period at server time t_ns [ns]: watchdog (hold when commands stop, events both ways),
  /// passivity port (a passivity scheme turns the command into the tool's target), world step.
  void step(std::int64_t t_ns, sim::EventQueue& events);

  /// Changes the physics period [s] (an in-process slave stepped at another rate).
  void set_period_s(double dt_s);
  double period_s() const { return dt_s_; }

  const sim::WorldModel& model() const { return model_; }
  const sim::WorldData& data() const { return data_; }
  const sim::WorldOutput& output() const { return data_.out; }
  /// The command the slave tracks (its seq and send time are echoed).
  const SlaveCommand& command() const { return command_; }
  /// The tracked command's send stamp, as the master wrote it [ns].
  std::int64_t command_send_time_ns() const { return send_time_ns_; }
  bool have_command() const { return have_command_; }
  /// The slave held its pose in the last step (watchdog, disabled command, or port).
  bool held() const { return held_; }
  /// The passivity port ran in the last step.
  bool port_active() const { return port_active_; }
  const passivity::SlavePassivityPort& port() const { return port_; }
  std::uint64_t steps() const { return steps_; }
  std::uint64_t watchdog_trips() const { return watchdog_trips_; }
  /// Commands whose K_ps (position_gain_n_per_m) was above max_gain_n_per_m() and was clamped.
  std::uint64_t gains_clamped() const { return gains_clamped_; }
  /// The largest K_ps the slave holds at the cycle's period (sim::max_position_gain_n_per_m).
  double max_gain_n_per_m() const { return max_gain_n_per_m_; }
  /// Reads the next step's data into the caches (sim::world_prewarm); changes nothing.
  std::uint64_t prewarm() const { return sim::world_prewarm(model_, data_); }
  /// Duration of the last world step [us].
  double step_time_us() const { return step_time_us_; }
  /// What the tip touches or is about to: the local model of the model-mediated scheme,
  /// estimated after each step (common/control/contact_model.hpp).
  const mmt::LocalModel& local_model() const { return estimator_.model(); }

 private:
  /// The nearest surface of the scene to the tip: its planes, and each deformable body as its
  /// bounding sphere at rest (nominal stiffness: its contact spring's).
  mmt::SurfacePrior nearest_surface(const Eigen::Vector3d& tip_m);

  struct BodySphere {
    std::int32_t id;
    Eigen::Vector3d centre_m;
    double radius_m, stiffness_n_per_m, damping_ns_per_m;
    Eigen::Matrix3Xd reference_x;  ///< the body's nodes when the tip began touching it
    bool reference_valid = false;
  };

  const sim::WorldModel& model_;
  sim::WorldData data_;
  double dt_s_;
  double max_gain_n_per_m_;
  std::int64_t timeout_ns_;
  SlaveCommand command_;
  sim::WorldCommand world_cmd_;
  passivity::SlavePassivityPort port_;
  std::int64_t receive_ns_ = 0;
  std::int64_t send_time_ns_ = 0;
  bool have_command_ = false;
  bool watchdog_holding_ = true;
  bool held_ = true;
  bool port_active_ = false;
  std::uint64_t steps_ = 0;
  std::uint64_t watchdog_trips_ = 0;
  std::uint64_t gains_clamped_ = 0;
  bool gain_clamping_ = false;        ///< the last command's K_ps was clamped
  bool clamp_event_pending_ = false;  ///< a clamp began: the next step reports it
  double step_time_us_ = 0.0;
  std::vector<BodySphere> spheres_;
  mmt::ContactEstimator estimator_;
};

}  // namespace teleop::server
