#include "server/node/server_cycle.hpp"

#include <cstdio>

#include "common/util/clock.hpp"

namespace teleop::server {

ServerCycle::ServerCycle(const sim::WorldModel& model, double dt_s, double command_timeout_s)
    : model_(model),
      data_(sim::make_world_data(model)),
      dt_s_(dt_s),
      max_gain_n_per_m_(sim::max_position_gain_n_per_m(model, 1.0 / dt_s)),
      timeout_ns_(static_cast<std::int64_t>(command_timeout_s * 1e9)) {
  // until a command arrives the slave holds where it starts
  world_cmd_.position_m = model.tool_start_m;
  world_cmd_.hold = true;
  for (std::size_t i = 0; i < model.bodies.size(); ++i) {
    const Eigen::Matrix3Xd& x = data_.bodies[i].state.x;
    const Eigen::Vector3d centre = x.rowwise().mean();
    const sim::DeformableBodyModel& b = model.bodies[i];
    // the stiffness the tip meets: measured on the body at load for fem, else its contact's
    spheres_.push_back({b.object_id, centre, (x.colwise() - centre).colwise().norm().maxCoeff(),
                        data_.bodies[i].contact_stiffness_n_per_m, b.contact.damping_ns_per_m, x,
                        false});
  }
}

mmt::SurfacePrior ServerCycle::nearest_surface(const Eigen::Vector3d& tip_m) {
  const double r = model_.tip_radius_m();
  mmt::SurfacePrior best;
  if (model_.has_robot()) {
    for (const sim::Plane& p : model_.planes) {
      best = mmt::nearer(best, mmt::plane_prior(p.id, p.normal, p.offset_m, r, tip_m,
                                                p.stiffness_n_per_m, p.damping_ns_per_m));
    }
  } else {
    // the tool's obstacles: the scene's planes, in order, and rigid spheres of worlds built in
    // code (sim::tool_world_model)
    const sim::ToolModel& t = model_.tool;
    for (int i = 0; i < t.obstacle_count; ++i) {
      const sim::Obstacle& o = t.obstacles[static_cast<std::size_t>(i)];
      best = mmt::nearer(best, o.kind == sim::Obstacle::Kind::kPlane
                                   ? mmt::plane_prior(o.id, o.normal, o.offset_m, r, tip_m,
                                                      o.stiffness_n_per_m, o.damping_ns_per_m)
                                   : mmt::sphere_prior(o.id, o.centre_m, o.radius_m, r, tip_m,
                                                       o.stiffness_n_per_m, o.damping_ns_per_m));
    }
  }
  for (std::size_t i = 0; i < spheres_.size(); ++i) {
    BodySphere& b = spheres_[i];
    mmt::SurfacePrior p = mmt::sphere_prior(b.id, b.centre_m, b.radius_m, r, tip_m,
                                            b.stiffness_n_per_m, b.damping_ns_per_m);
    // while the tip presses the body, its surface is where it was when the touch began (the
    // dent is the depth, not a new surface); the nodes are copied once per touch
    const bool touching = data_.bodies[i].last.in_contact;
    if (touching && !b.reference_valid) {
      b.reference_x = data_.bodies[i].state.x;  // same size: no allocation
      b.reference_valid = true;
    } else if (!touching) {
      b.reference_valid = false;
    }
    if (p.valid && p.distance_m < 0.2) {
      // near it: the body as it is (it sags under gravity), by its support point in the
      // direction of the tip: the tangent plane of its nodes' hull facing the tip
      const Eigen::Matrix3Xd& x = b.reference_valid ? b.reference_x : data_.bodies[i].state.x;
      double support = -1e30;
      for (Eigen::Index k = 0; k < x.cols(); ++k)
        support = std::max(support, p.normal.dot(x.col(k)));
      p.offset_m = support + r;
      p.distance_m = p.normal.dot(tip_m) - p.offset_m;
    }
    best = mmt::nearer(best, p);
  }
  return best;
}

void ServerCycle::on_command(const SlaveCommand& c, std::int64_t receive_ns,
                             std::int64_t send_time_ns) {
  send_time_ns_ = send_time_ns;
  command_ = c;
  world_cmd_ = sim::to_world_command(c);
  // a K_ps the slave cannot hold at its rate is clamped to the largest it can, and counted
  const bool clamp = world_cmd_.kp_override_n_per_m > max_gain_n_per_m_;
  if (clamp) {
    world_cmd_.kp_override_n_per_m = max_gain_n_per_m_;
    ++gains_clamped_;
    if (!gain_clamping_) clamp_event_pending_ = true;
  }
  gain_clamping_ = clamp;
  receive_ns_ = receive_ns;
  have_command_ = true;
}

void ServerCycle::set_period_s(double dt_s) {
  dt_s_ = dt_s;
  max_gain_n_per_m_ = sim::max_position_gain_n_per_m(model_, 1.0 / dt_s);
}

void ServerCycle::step(std::int64_t t_ns, sim::EventQueue& events) {
  const double sim_time_s = data_.out.sim_time_s;
  if (clamp_event_pending_) {
    clamp_event_pending_ = false;
    char text[sizeof(sim::SimEvent::message)];
    std::snprintf(text, sizeof(text),
                  "command position_gain_n_per_m %.6g N/m clamped: the slave holds 0-%.6g N/m "
                  "at its rate",
                  command_.position_gain_n_per_m, max_gain_n_per_m_);
    sim::EventTags tags;
    tags.subject = sim::EventSubject::kPositionGain;
    events.push(sim::EventKind::kLimit, sim::Severity::kWarning, sim_time_s,
                command_.position_gain_n_per_m, text, tags);
  }
  // watchdog: hold the slave when commands stop arriving
  const bool stale = !have_command_ || (t_ns - receive_ns_) > timeout_ns_;
  if (stale != watchdog_holding_) {
    watchdog_holding_ = stale;
    if (have_command_ && stale) {
      ++watchdog_trips_;
      events.push(sim::EventKind::kWatchdog, sim::Severity::kWarning, sim_time_s,
                  seconds_between(receive_ns_, t_ns) * 1e3,
                  "no valid command within the timeout: holding the slave");
    } else if (have_command_) {
      events.push(sim::EventKind::kWatchdog, sim::Severity::kInfo, sim_time_s, 0.0,
                  "commands resumed: tracking again");
    }
  }
  sim::WorldCommand applied = world_cmd_;
  applied.hold = world_cmd_.hold || watchdog_holding_;

  // passivity schemes: the port turns the command into the tool's target, using the state
  // and contact force of the last step
  const passivity::SlavePortCommand port_cmd = passivity::port_command(command_);
  port_active_ = have_command_ && passivity::SlavePassivityPort::handles(port_cmd.scheme);
  if (port_active_) {
    passivity::SlavePortCommand pc = port_cmd;
    pc.enabled = !applied.hold;
    const sim::WorldOutput& before = data_.out;
    const passivity::SlavePortState ps{before.tip_position_m, before.tip_velocity_mps,
                                       before.contact_force_n};
    const passivity::TrackingGains gains{applied.kp_override_n_per_m > 0.0
                                             ? applied.kp_override_n_per_m
                                             : model_.tracking_kp_n_per_m(),
                                         model_.tracking_kd_ns_per_m()};
    const passivity::SlavePortTarget t = port_.before_step(pc, ps, gains, dt_s_);
    applied.position_m = t.position_m;
    applied.velocity_mps = t.velocity_mps;
    applied.hold = t.hold;
  } else if (port_.scheme() != 0xff) {
    port_.reset();  // left the passivity scheme: the next session starts afresh
  }

  const std::int64_t ts = now_ns();
  sim::world_step(model_, data_, applied, dt_s_, events);
  step_time_us_ = static_cast<double>(now_ns() - ts) * 1e-3;
  if (port_active_) port_.after_step(data_.out.tracking_force_n, dt_s_);
  const sim::WorldOutput& o = data_.out;
  estimator_.update(o.tip_position_m, o.tip_velocity_mps, o.contact_force_n, o.in_contact,
                    nearest_surface(o.tip_position_m));
  held_ = applied.hold;
  ++steps_;
}

}  // namespace teleop::server
