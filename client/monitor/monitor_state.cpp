#include "client/monitor/monitor_state.hpp"

#include "common/dds/event_kinds.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdarg>
#include <cstdio>

#include "common/dds/experiment_text.hpp"
#include "common/util/json.hpp"

namespace teleop::monitor {

namespace {

std::string fmt(const char* f, ...) {
  char buf[512];
  va_list ap;
  va_start(ap, f);
  std::vsnprintf(buf, sizeof(buf), f, ap);
  va_end(ap);
  return buf;
}

OrderedJson vec3(const std::array<double, 3>& v) {
  return OrderedJson::array({json_number(v[0]), json_number(v[1]), json_number(v[2])});
}

std::uint64_t rejected(const ServerStats& s) {
  return s.commands_rejected_nan() + s.commands_rejected_workspace() + s.commands_rejected_stale() +
         s.commands_rejected_passivity();
}

}  // namespace

const TopicView* Snapshot::topic(const std::string& name) const {
  for (const auto& t : topics) {
    if (t.name == name) return &t;
  }
  return nullptr;
}

bool Snapshot::waiting() const {
  for (const char* n : {"slave_state", "server_stats", "scene"}) {
    const TopicView* t = topic(n);
    if (t && t->seen()) return false;
  }
  return true;
}

std::string Snapshot::status() const {
  if (waiting()) {
    return fmt("waiting for a server on domain %d (profile %s)", domain, profile.c_str());
  }
  const TopicView* st = topic("slave_state");
  if (!st || !st->seen()) return "server present, no slave_state yet";
  if (st->stale()) return fmt("STALE: no slave_state for %.1f s (server gone?)", st->age_s);
  std::string live = server.empty() ? "LIVE" : "LIVE: server " + server;
  if (servers > 1) live += fmt("; WARNING: %d participants write the server's topics", servers);
  return live;
}

std::string scene_line(const SceneDescription& d) {
  return fmt("scene '%s': %zu objects, %u joints, physics %.0f Hz, tip radius %.3f m",
             d.name().c_str(), d.objects().size(), d.joint_count(), d.physics_rate_hz(),
             d.tip_radius_m());
}

std::string event_line(const EventView& e) {
  return fmt("event %-7s %-13s %s (%.3g)", e.event.source().c_str(),
             dds::event_kind_name(e.event.kind()), e.event.message().c_str(), e.event.value());
}

std::string experiment_line(const Snapshot& s) {
  if (!s.have_experiment) return "experiment (none yet: no master has described its session)";
  // latched: the description stays after its master left, and says so
  const TopicView* m = s.topic("master_state");
  const bool gone = m && m->stale();
  return std::string(gone ? "experiment (master gone, its last description) " : "experiment ") +
         dds::experiment_text(s.experiment);
}

namespace {

OrderedJson experiment_fields(const ExperimentDescription& e) {
  OrderedJson o;
  o["session"] = e.master_session();
  o["scheme"] = e.scheme().to_string();
  o["master_stiffness_n_per_m"] = json_number(e.master_stiffness_n_per_m());
  o["master_damping_ns_per_m"] = json_number(e.master_damping_ns_per_m());
  o["force_gain"] = json_number(e.force_gain());
  o["slave_stiffness_n_per_m"] = json_number(e.slave_stiffness_n_per_m());
  o["forward_delay_ms"] = json_number(e.forward_delay_ms());
  o["backward_delay_ms"] = json_number(e.backward_delay_ms());
  o["forward_jitter_ms"] = json_number(e.forward_jitter_ms());
  o["backward_jitter_ms"] = json_number(e.backward_jitter_ms());
  o["forward_jitter_dist"] = e.forward_jitter_dist().to_string();
  o["backward_jitter_dist"] = e.backward_jitter_dist().to_string();
  o["forward_loss"] = json_number(e.forward_loss());
  o["backward_loss"] = json_number(e.backward_loss());
  o["forward_burst"] = OrderedJson::array(
      {json_number(e.forward_burst_p_gb()), json_number(e.forward_burst_p_bg())});
  o["backward_burst"] = OrderedJson::array(
      {json_number(e.backward_burst_p_gb()), json_number(e.backward_burst_p_bg())});
  o["seeds"] = OrderedJson::array({e.forward_seed(), e.backward_seed()});
  o["rate_hz"] = json_number(e.rate_hz());
  o["loop_delay_p50_ms"] = json_number(e.loop_delay_p50_ms());
  o["loop_delay_p99_ms"] = json_number(e.loop_delay_p99_ms());
  o["device"] = e.device().to_string();
  o["driver_live"] = e.driver_live();
  o["driver_silences"] = e.driver_silences();
  o["driver_silent_s"] = json_number(e.driver_silent_s());
  o["driver_timeout_ms"] = json_number(e.driver_timeout_ms());
  return o;
}

}  // namespace

std::string experiment_json(const ExperimentDescription& e) {
  return json_line(experiment_fields(e));
}

namespace {

std::string slave_text(const Snapshot& s, const TopicView* t) {
  if (!s.have_slave) return "";
  if (t && t->stale()) return fmt("slave   STALE: no slave_state for %.1f s", t->age_s);
  const auto& x = s.slave.tip_position_m();
  const auto& f = s.slave.contact_force_n();
  return fmt(
      "slave   tip (%.3f, %.3f, %.3f) m  contact %s  force (%.2f, %.2f, %.2f) N  "
      "penetration %.2f mm%s",
      x[0], x[1], x[2], s.slave.in_contact() ? "yes" : "no ", f[0], f[1], f[2],
      s.slave.penetration_m() * 1e3, s.slave.holding() ? "  HOLDING" : "");
}

std::string master_text(const Snapshot& s, const TopicView* t) {
  if (!s.have_master) return "";
  if (t && t->stale()) return fmt("master  STALE: no master_state for %.1f s", t->age_s);
  const auto& fm = s.master.rendered_force_n();
  return fmt("master  rtt %.3f ms  rendered force (%.2f, %.2f, %.2f) N  error %.1f mm  link %s",
             s.master.rtt_ms(), fm[0], fm[1], fm[2], s.master.position_error_m() * 1e3,
             s.master.link_ok() ? "ok" : "LOST");
}

std::string server_text(const Snapshot& s, const TopicView* t) {
  if (!s.have_stats) return "";
  if (t && t->stale()) return fmt("server  STALE: no server_stats for %.1f s", t->age_s);
  return fmt(
      "server  loop %.0f Hz  step p50 %.1f us p99 %.1f us  overruns %llu  rejected %llu  "
      "watchdog %llu",
      s.stats.loop_rate_hz(), s.stats.step_us_p50(), s.stats.step_us_p99(),
      static_cast<unsigned long long>(s.stats.overruns()),
      static_cast<unsigned long long>(rejected(s.stats)),
      static_cast<unsigned long long>(s.stats.watchdog_trips()));
}

}  // namespace

std::vector<std::string> render_screen(const Snapshot& s, int rows, int cols) {
  std::vector<std::string> out;
  out.push_back(fmt("teleop_monitor  domain %d  profile %s%s  up %.1f s   (q: quit)", s.domain,
                    s.profile.c_str(), s.insecure ? " INSECURE (no DDS Security)" : "", s.t_s));
  out.push_back("status  " + s.status());
  out.push_back(s.full_rate ? "topics  full rate (--full-rate): every sample"
                            : "topics  10 Hz monitor copies (*_monitor); master_command counted "
                              "by the server; --full-rate for every sample");
  out.push_back(s.have_scene ? scene_line(s.scene) : "scene   (none yet)");
  out.push_back(experiment_line(s));
  out.push_back("");
  out.push_back(fmt("%-22s %10s %12s %10s", "topic", "rate Hz", "age", "samples"));
  for (const auto& t : s.topics) {
    std::string age;
    if (!t.seen()) {
      age = "-";
    } else if (t.latched) {
      age = "latched";
    } else {
      age = fmt("%.3f s", t.age_s);
    }
    out.push_back(fmt("%-22s %10.1f %12s %10llu%s", t.name.c_str(), t.rate_hz, age.c_str(),
                      static_cast<unsigned long long>(t.count), t.stale() ? "  STALE" : ""));
  }
  out.push_back("");
  for (const std::string& line :
       {slave_text(s, s.topic("slave_state")), master_text(s, s.topic("master_state")),
        server_text(s, s.topic("server_stats"))}) {
    if (!line.empty()) out.push_back(line);
  }
  out.push_back("");
  out.push_back("events (newest last)");
  const int room = std::max(1, rows - static_cast<int>(out.size()));
  const int first = std::max(0, static_cast<int>(s.events.size()) - room);
  for (int i = first; i < static_cast<int>(s.events.size()); ++i) {
    out.push_back(fmt("%8.1f s  ", s.events[static_cast<std::size_t>(i)].at_s) +
                  event_line(s.events[static_cast<std::size_t>(i)]).substr(6));
  }
  if (static_cast<int>(out.size()) > rows) out.resize(static_cast<std::size_t>(rows));
  for (auto& l : out) {
    if (cols > 0 && static_cast<int>(l.size()) > cols) l.resize(static_cast<std::size_t>(cols));
  }
  return out;
}

std::string render_lines(const Snapshot& s) {
  auto rate = [&](const char* n) {
    const TopicView* t = s.topic(n);
    return t ? t->rate_hz : 0.0;
  };
  std::string o;
  if (s.waiting()) o += s.status() + "\n";
  o += fmt("t=%6.1fs  slave_state %6.0f Hz  master_state %5.0f Hz  mesh %4.0f Hz", s.t_s,
           rate("slave_state"), rate("master_state"), rate("mesh_frame"));
  const std::string server = server_text(s, s.topic("server_stats"));
  if (!server.empty()) o += "  | " + server.substr(8);
  o += "\n";
  const std::string slave = slave_text(s, s.topic("slave_state"));
  if (!slave.empty()) o += "           " + slave.substr(8) + "\n";
  const std::string master = master_text(s, s.topic("master_state"));
  if (!master.empty()) o += "           master " + master.substr(8) + "\n";
  if (s.have_experiment) o += "           " + experiment_line(s) + "\n";
  return o;
}

namespace {

OrderedJson topics_fields(const Snapshot& s) {
  OrderedJson topics = OrderedJson::object();
  for (const auto& t : s.topics) {
    topics[t.name] = {{"count", t.count},
                      {"rate_hz", json_number(t.rate_hz)},
                      {"age_s", t.seen() ? json_number(t.age_s) : OrderedJson(nullptr)},
                      {"stale", t.stale()}};
  }
  return topics;
}

OrderedJson server_fields(const ServerStats& st) {
  return {{"loop_rate_hz", json_number(st.loop_rate_hz())},
          {"step_us_p50", json_number(st.step_us_p50())},
          {"step_us_p99", json_number(st.step_us_p99())},
          {"overruns", st.overruns()},
          {"rejected", rejected(st)},
          {"watchdog_trips", st.watchdog_trips()},
          {"matched_state_readers", st.matched_state_readers()}};
}

}  // namespace

std::string render_json(const Snapshot& s) {
  OrderedJson o;
  o["type"] = "status";
  o["t"] = json_number(s.t_s);
  o["domain"] = s.domain;
  o["profile"] = s.profile;
  o["insecure"] = s.insecure;
  o["full_rate"] = s.full_rate;
  o["waiting"] = s.waiting();
  o["status"] = s.status();
  o["topics"] = topics_fields(s);
  // a stale topic's last sample is not shown as live
  const auto live = [&s](const char* topic) {
    const TopicView* t = s.topic(topic);
    return !(t && t->stale());
  };
  o["slave"] = nullptr;
  if (s.have_slave && live("slave_state")) {
    o["slave"] = {{"tip_m", vec3(s.slave.tip_position_m())},
                  {"contact_force_n", vec3(s.slave.contact_force_n())},
                  {"penetration_m", json_number(s.slave.penetration_m())},
                  {"in_contact", s.slave.in_contact()},
                  {"holding", s.slave.holding()}};
  }
  o["master"] = nullptr;
  if (s.have_master && live("master_state")) {
    o["master"] = {{"rtt_ms", json_number(s.master.rtt_ms())},
                   {"rendered_force_n", vec3(s.master.rendered_force_n())},
                   {"position_error_m", json_number(s.master.position_error_m())},
                   {"link_ok", s.master.link_ok()}};
  }
  o["server"] =
      s.have_stats && live("server_stats") ? server_fields(s.stats) : OrderedJson(nullptr);
  o["experiment"] = s.have_experiment ? experiment_fields(s.experiment) : OrderedJson(nullptr);
  return json_line(o);
}

std::string event_json(const EventView& e) {
  OrderedJson o;
  o["type"] = "event";
  o["t"] = json_number(e.at_s);
  o["source"] = e.event.source().to_string();
  o["kind"] = dds::event_kind_name(e.event.kind());
  o["severity"] = static_cast<int>(e.event.severity());
  o["message"] = e.event.message().to_string();
  o["value"] = json_number(e.event.value());
  return json_line(o);
}

std::string scene_json(const SceneDescription& d) {
  // each deformable body's automatic step: its stable step and the sub-steps it takes
  OrderedJson deformables = OrderedJson::array();
  for (const SceneObject& ob : d.objects()) {
    if (ob.kind() != OBJECT_DEFORMABLE_MESH) continue;
    deformables.push_back({{"id", ob.id()},
                           {"highest_frequency_radps", json_number(ob.highest_frequency_radps())},
                           {"stable_step_s", json_number(ob.stable_step_s())},
                           {"substeps", ob.substeps()}});
  }
  OrderedJson o;
  o["type"] = "scene";
  o["name"] = d.name().to_string();
  o["objects"] = d.objects().size();
  o["joints"] = d.joint_count();
  o["physics_rate_hz"] = json_number(d.physics_rate_hz());
  o["tip_radius_m"] = json_number(d.tip_radius_m());
  o["deformables"] = std::move(deformables);
  return json_line(o);
}

}  // namespace teleop::monitor
