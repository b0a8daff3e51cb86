#include "client/node/master_session.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "client/device/operator_model.hpp"
#include "client/node/master_node.hpp"
#include "client/node/master_report.hpp"

namespace teleop::master {

namespace {

/// The simulated device's script as --script names it (its length is all the plan needs).
OperatorScript device_script(const MasterOptions& options) {
  if (options.script == "press-slip") {
    return press_slip_script(Eigen::Vector3d::Zero(), options.press_depth_m);
  }
  OperatorScript s;
  s.kind = parse_script_kind(options.script);
  return s;
}

}  // namespace

SessionPlan plan_session(const MasterOptions& options) {
  SessionPlan p;
  p.samples = options.samples;
  p.state_every = std::max<std::uint64_t>(
      1, static_cast<std::uint64_t>(std::llround(options.rate_hz / options.state_rate_hz)));
  if (options.duration_s > 0) {
    p.session_length_s = options.duration_s;
  } else if (options.device == "simulated") {
    p.session_length_s = std::max(2.0, script_duration_s(device_script(options)) + 1.0);
  } else {
    p.session_length_s = 10.0;
  }
  p.grace_s = 0.5 + 2.0 * (options.forward.delay_s + options.backward.delay_s);
  p.wait_owner_s = options.wait_owner_s;
  return p;
}

MasterSession::MasterSession(const SessionPlan& plan, std::int64_t t0_ns)
    : plan_(plan),
      t0_ns_(t0_ns),
      t0_s_(static_cast<double>(t0_ns) * 1e-9),
      owner_(t0_s_, plan.grace_s, plan.wait_owner_s) {
  plan_.state_every = std::max<std::uint64_t>(1, plan_.state_every);
}

bool MasterSession::over(double now_s, bool homing, double session_start_s) const {
  if (plan_.samples > 0 && cycles_ >= plan_.samples) return true;
  if (owner_.give_up()) return true;
  return !homing && now_s - session_start_s >= plan_.session_length_s;
}

double MasterSession::begin_cycle(double now_s) {
  ++cycles_;
  return stalls_.cycle_began(now_s);
}

bool MasterSession::faults_rose(std::uint64_t faults) {
  if (faults <= faults_seen_) return false;
  faults_seen_ = faults;
  return true;
}

void MasterSession::link_state(bool lost) {
  if (lost && !link_lost_) ++link_losses_;
  link_lost_ = lost;
}

void MasterSession::report(double end_s, double session_start_s, SessionReport& rep) const {
  rep.elapsed_s = end_s - t0_s_;
  rep.session_s = session_start_s < 0 ? 0.0 : end_s - session_start_s;
  rep.loop_delay_ms = loop_delay_.summary();
  rep.refused = owner_.give_up();
  rep.refused_first = owner_.refused_first();
  rep.waited_for_owner_s = owner_.waited_s(end_s);
  rep.stalls = stalls_.stalls();
  rep.longest_stall_s = stalls_.longest_s();
  rep.link_losses = link_losses_;
}

}  // namespace teleop::master
