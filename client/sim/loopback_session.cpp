#include "client/sim/loopback_session.hpp"

#include <cstdio>

#include "common/util/json.hpp"
#include "common/util/version.hpp"

namespace teleop::master {

MasterCycleConfig LoopbackSession::cycle_config(const LoopbackConfig& cfg) {
  MasterCycleConfig c = cfg;
  c.delivery = ForwardDelivery::kNewestDue;  // the slave steps with the newest command
  return c;
}

LoopbackSession::LoopbackSession(const LoopbackConfig& cfg, HapticDevice& device,
                                 SlaveSimulator& slave)
    : cfg_(cfg), slave_(slave), cycle_(cycle_config(cfg), device, link_) {}

void LoopbackSession::start() {
  if (cfg_.homing_s > 0.0) {
    cycle_.start_homing(0.0, slave_.sample().position_m, cfg_.homing_s);
  } else {
    cycle_.start(0.0);
    slave_.reset(cfg_.controller.workspace.to_slave_position(cycle_.reading().position_m));
  }
  link_.command = SlaveCommand{};
  link_.command.enabled = false;  // hold until the first command arrives
  link_.pending = false;
  t_s_ = 0.0;
  started_ = true;
}

bool LoopbackSession::step() {
  if (cfg_.homing_s > 0.0) {
    // as teleop_master: the session's length counts from the end of homing
    if (!cycle_.homing() && t_s_ - cycle_.session_start_s() >= cfg_.duration_s - 0.5 * cfg_.dt_s)
      return false;
  } else if (t_s_ >= cfg_.duration_s - 0.5 * cfg_.dt_s) {
    return false;
  }
  const double now = t_s_;
  cycle_.step(now);
  // the slave steps with the newest command it has; its sample travels back next cycle
  slave_.step(link_.command, cfg_.dt_s);
  const SlaveSample truth = slave_.sample();
  if (!link_.outage) {
    link_.sample = truth;
    link_.sample_at_s = now;
    link_.pending = true;
  }
  // metrics from the slave's ground truth, since both run here
  cycle_.finish(now, &truth);
  t_s_ += cfg_.dt_s;
  return true;
}

void LoopbackSession::run() {
  if (!started_) start();
  while (step()) {
  }
}

std::string LoopbackSession::summary_json() const {
  OrderedJson s;
  s["scheme"] = controller().name();
  s["metrics"] = metrics().summary_fields();
  s["transparency"] = metrics().transparency_fields();
  s["forward"] = channel_fields(forward().report());
  s["backward"] = channel_fields(backward().report());
  s["safety"] = {{"cut", safety().cut()}, {"reason", safety().cut_reason()}};
  s["version"] = version_string();
  return json_compact(s);
}

}  // namespace teleop::master
