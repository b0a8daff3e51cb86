#include "server/node/resim.hpp"

#include <cmath>
#include <cstring>

#include "common/dds/checked_type.hpp"
#include "common/dds/teleop_idl.hpp"
#include "server/node/command_gate.hpp"
#include "server/node/server_cycle.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::server {
namespace {

/// 64-bit FNV-1a, fed field by field (the bytes of each double as stored).
struct Fnv1a {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  void bytes(const void* p, std::size_t n) {
    const auto* b = static_cast<const unsigned char*>(p);
    for (std::size_t i = 0; i < n; ++i) {
      h ^= b[i];
      h *= 0x100000001b3ULL;
    }
  }
  void f64(double v) { bytes(&v, sizeof v); }
  void u64(std::uint64_t v) { bytes(&v, sizeof v); }
  void vec(const Eigen::Vector3d& v) {
    for (int i = 0; i < 3; ++i) f64(v[i]);
  }
};

/// The writer's GUID (32 hex digits) as the node's writer id.
WriterId writer_id(const std::string& hex) {
  WriterId w;
  for (std::size_t i = 0; i < w.bytes.size() && 2 * i + 1 < hex.size(); ++i) {
    auto nibble = [](char c) -> std::uint8_t {
      if (c >= '0' && c <= '9') return static_cast<std::uint8_t>(c - '0');
      if (c >= 'a' && c <= 'f') return static_cast<std::uint8_t>(c - 'a' + 10);
      if (c >= 'A' && c <= 'F') return static_cast<std::uint8_t>(c - 'A' + 10);
      return 0;
    };
    w.bytes[i] = static_cast<std::uint8_t>(nibble(hex[2 * i]) << 4 | nibble(hex[2 * i + 1]));
  }
  return w;
}

/// The node's edge (command_gate.hpp) on one stream row: true (and `out` set) when the row is
/// a command the node would hand to the cycle.
bool accept(CommandGate& gate, const StreamedCommand& row, MasterCommand& out, ResimResult& r) {
  eprosima::fastrtps::rtps::SerializedPayload_t payload(
      static_cast<std::uint32_t>(row.payload.size()));
  std::memcpy(payload.data, row.payload.data(), row.payload.size());
  payload.length = static_cast<std::uint32_t>(row.payload.size());
  if (!dds::deserialize_checked<MasterCommandPubSubType>(payload, out)) {
    ++r.undecodable;
    return false;
  }
  return gate.pass(out, writer_id(row.writer), row.receive_ns);
}

void hash_step(Fnv1a& h, const ResimStep& s) {
  const sim::WorldOutput& o = *s.out;
  h.u64(s.step);
  h.f64(o.sim_time_s);
  h.u64(s.command_seq);
  h.u64(s.holding ? 1 : 0);
  h.vec(o.tip_position_m);
  h.f64(o.tip_orientation.w());
  h.f64(o.tip_orientation.x());
  h.f64(o.tip_orientation.y());
  h.f64(o.tip_orientation.z());
  h.vec(o.tip_velocity_mps);
  h.vec(o.contact_force_n);
  h.vec(o.contact_torque_nm);
  h.f64(o.penetration_m);
  h.f64(o.deformation_m);
  h.u64(o.in_contact ? 1 : 0);
  h.u64(static_cast<std::uint64_t>(static_cast<std::int64_t>(o.contact_object)));
  for (int j = 0; j < o.joint_count; ++j) h.f64(o.q_rad[static_cast<std::size_t>(j)]);
}

void hash_event(Fnv1a& h, const sim::SimEvent& e) {
  h.u64(static_cast<std::uint64_t>(e.kind));
  h.u64(static_cast<std::uint64_t>(e.severity));
  h.f64(e.value);
  h.f64(e.sim_time_s);
  h.bytes(e.message, std::strlen(e.message));
}

}  // namespace

ResimResult resimulate(const sim::WorldModel& model, const std::vector<StreamedCommand>& stream,
                       const ResimOptions& options,
                       const std::function<void(const ResimStep&)>& on_step,
                       const std::function<void(const sim::SimEvent&)>& on_event) {
  ResimResult r;
  r.commands = stream.size();
  if (stream.empty()) return r;
  const double dt_s = 1.0 / options.rate_hz;
  const auto dt_ns = static_cast<std::int64_t>(std::llround(1e9 * dt_s));
  ServerCycle cycle(model, dt_s, model.command_timeout_s);
  CommandGate gate(model.workspace_min_m, model.workspace_max_m,
                   static_cast<std::int64_t>(std::llround(1e9 * options.owner_timeout_s)));
  sim::EventQueue events;
  Fnv1a h;
  const std::int64_t t0 = stream.front().receive_ns;
  const std::int64_t t_end =
      stream.back().receive_ns + static_cast<std::int64_t>(std::llround(1e9 * options.tail_s));
  std::size_t next = 0;
  MasterCommand cmd, newest;
  for (std::int64_t t = t0; t <= t_end; t += dt_ns) {
    bool have_newest = false;
    std::int64_t newest_receive = 0;
    for (; next < stream.size() && stream[next].receive_ns <= t; ++next) {
      if (accept(gate, stream[next], cmd, r)) {
        newest = cmd;
        newest_receive = stream[next].receive_ns;
        have_newest = true;
      }
    }
    if (have_newest) cycle.on_command(from_idl(newest), newest_receive, newest.send_time_ns());
    cycle.step(t, events);
    ResimStep s;
    s.step = r.steps++;
    s.sim_time_s = cycle.output().sim_time_s;
    s.command_seq = cycle.command().seq;
    s.holding = cycle.held();
    s.out = &cycle.output();
    hash_step(h, s);
    if (on_step) on_step(s);
    sim::SimEvent e;
    while (events.pop(e)) {
      ++r.events;
      hash_event(h, e);
      if (on_event) on_event(e);
    }
  }
  const GateCounts& c = gate.counts();
  r.accepted = c.accepted;
  r.rejected_nan = c.rejected_nan;
  r.rejected_workspace = c.rejected_workspace;
  r.rejected_stale = c.rejected_stale;
  r.rejected_passivity = c.rejected_passivity;
  r.refused_owner = c.refused_owner;
  r.masters = gate.ownership().changes();
  r.watchdog_trips = cycle.watchdog_trips();
  r.hash = h.h;
  return r;
}

}  // namespace teleop::server
