#include "common/control/slave_port.hpp"

#include <cmath>

namespace teleop::passivity {

const char* to_string(PortCommandCheck c) {
  switch (c) {
    case PortCommandCheck::kOk:
      return "ok";
    case PortCommandCheck::kNonFinite:
      return "non-finite wave or energy field";
    case PortCommandCheck::kBadImpedance:
      return "wave impedance out of range";
    case PortCommandCheck::kNegativeEnergy:
      return "negative energy";
    case PortCommandCheck::kEnergyDecreased:
      return "cumulative energy decreased (stale or corrupt)";
  }
  return "?";
}

PortCommandCheck check_port_command(const SlavePortCommand& c) {
  if (!ports_finite(c) || !c.position_m.allFinite() || !c.velocity_mps.allFinite()) {
    return PortCommandCheck::kNonFinite;
  }
  bool in = true;
  for_each_port([&in, &c](const auto& p) { in = in && in_range(p, c.scheme); }, c);
  if (!in) {
    return PortCommandCheck::kBadImpedance;
  }
  bool negative = false;
  for_each_port([&negative](const auto& p) { negative = negative || any_negative(p); }, c);
  if (negative) {
    return PortCommandCheck::kNegativeEnergy;
  }
  return PortCommandCheck::kOk;
}

bool energy_decreased(const SlavePortCommand& now, const SlavePortCommand& last, double tol_j) {
  bool decreased_energy = false;
  for_each_port(
      [&decreased_energy, tol_j](const auto& n, const auto& l) {
        decreased_energy = decreased_energy || decreased(n, l, tol_j);
      },
      now, last);
  return decreased_energy;
}

void SlavePassivityPort::reset() {
  wave_.reset();
  tdpa_.reset();
  report_ = SlavePortReport{};
  scheme_ = 0xff;
  session_ = 0;
  active_ = false;
  stepped_tdpa_ = false;
  last_ = SlavePortCommand{};
}

void SlavePassivityPort::start(const SlavePortCommand& cmd) {
  scheme_ = cmd.scheme;
  session_ = cmd.session;
  active_ = true;
  wave_.start(cmd.wave);
  tdpa_.start(params_.drift_time_constant_s);
  report_ = SlavePortReport{};
  report_.session = cmd.session;
  last_ = SlavePortCommand{};
}

SlavePortTarget SlavePassivityPort::before_step(const SlavePortCommand& cmd,
                                                const SlavePortState& state,
                                                const TrackingGains& gains, double dt_s) {
  stepped_tdpa_ = false;
  SlavePortTarget t;
  if (!handles(cmd.scheme)) {
    // another scheme: pass the command through; a later passivity session starts afresh
    active_ = false;
    report_ = SlavePortReport{};
    t.position_m = cmd.position_m;
    t.velocity_mps = cmd.velocity_mps;
    t.hold = !cmd.enabled;
    return t;
  }
  t.hold = true;  // until proven usable
  if (check_port_command(cmd) != PortCommandCheck::kOk) {
    ++rejected_;
    report_.wave.v.setZero();
    return t;
  }
  if (!active_ || cmd.session != session_ || cmd.scheme != scheme_) start(cmd);
  // cumulative energies never decrease within a session: an older one is stale or corrupt
  constexpr double kTol = 1e-12;
  if (energy_decreased(cmd, last_, kTol)) {
    ++rejected_;
    report_.wave.v.setZero();
    return t;
  }
  last_ = cmd;
  if (!cmd.enabled) {
    // clutch open: the slave holds; waves are not consumed (the receiver catches up later)
    report_.wave.v.setZero();
    if (scheme_ == kSchemeTimeDomainPassivity) tdpa_.hold();
    return t;
  }
  t.hold = false;
  if (scheme_ == kSchemeWaveVariables) {
    wave_.before_step(cmd.wave, cmd.position_m, state.contact_force_n, dt_s, t.position_m,
                      t.velocity_mps, report_.wave, report_.dissipated_j);
  } else {
    tdpa_.before_step(cmd.position_m, cmd.tdpa, state.position_m, state.velocity_mps,
                      gains.kp_n_per_m, gains.kd_ns_per_m, dt_s, t.position_m, t.velocity_mps);
    stepped_tdpa_ = true;
  }
  return t;
}

void SlavePassivityPort::after_step(const Vec3& tracking_force_n, double dt_s) {
  if (!stepped_tdpa_) return;
  tdpa_.after_step(tracking_force_n, dt_s, report_.tdpa, report_.dissipated_j);
  stepped_tdpa_ = false;
}

SlavePortCommand port_command(const SlaveCommand& c) {
  SlavePortCommand p;
  p.scheme = static_cast<std::uint8_t>(c.scheme);
  p.session = c.passivity_session;
  p.enabled = c.enabled;
  p.position_m = c.position_m;
  p.velocity_mps = c.velocity_mps;
  for_each_port([](auto& dst, const auto& src) { dst = src; }, p, c);
  return p;
}

void apply_port_report(const SlavePortReport& r, SlaveSample& s) {
  s.passivity_session = r.session;
  for_each_port([](auto& dst, const auto& src) { dst = src; }, s, r);
  s.passivity_dissipated_j = r.dissipated_j;
}

}  // namespace teleop::passivity
