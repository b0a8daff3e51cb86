#include "server/node/resim.hpp"

#include <cmath>
#include <cstring>

#include "common/dds/checked_type.hpp"
#include "common/dds/teleop_idl.hpp"
#include "server/node/command_validation.hpp"
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

/// The node's edge validation (server_node.cpp on_command), on one stream row.
class EdgeValidator {
 public:
  explicit EdgeValidator(const sim::WorldModel& model) : model_(model) {}

  /// True (and `out` set) when the row is a valid command the node would hand to the cycle.
  bool accept(const StreamedCommand& row, MasterCommand& out, ResimResult& r) {
    eprosima::fastrtps::rtps::SerializedPayload_t payload(
        static_cast<std::uint32_t>(row.payload.size()));
    std::memcpy(payload.data, row.payload.data(), row.payload.size());
    payload.length = static_cast<std::uint32_t>(row.payload.size());
    if (!dds::deserialize_checked<MasterCommandPubSubType>(payload, out)) {
      ++r.undecodable;
      return false;
    }
    if (!have_writer_ || row.writer != writer_) {  // a new master restarts the numbering
      have_writer_ = true;
      writer_ = row.writer;
      have_last_ = false;
      history_ = PassivityHistory{};
      ++r.masters;
    }
    CommandVerdict v = validate_command(out, model_.workspace_min_m, model_.workspace_max_m,
                                        last_seq_, have_last_);
    if (v == CommandVerdict::kAccepted) v = validate_passivity(out, history_);
    switch (v) {
      case CommandVerdict::kAccepted:
        have_last_ = true;
        last_seq_ = out.seq();
        ++r.accepted;
        return true;
      case CommandVerdict::kOutsideWorkspace:
        ++r.rejected_workspace;
        return false;
      case CommandVerdict::kStale:
        ++r.rejected_stale;
        return false;
      case CommandVerdict::kBadPassivity:
        ++r.rejected_passivity;
        return false;
      default:
        ++r.rejected_nan;
        return false;
    }
  }

 private:
  const sim::WorldModel& model_;
  bool have_writer_ = false;
  std::string writer_;
  bool have_last_ = false;
  std::uint64_t last_seq_ = 0;
  PassivityHistory history_;
};

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
  EdgeValidator edge(model);
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
      if (edge.accept(stream[next], cmd, r)) {
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
  r.watchdog_trips = cycle.watchdog_trips();
  r.hash = h.h;
  return r;
}

}  // namespace teleop::server
