#include "client/monitor/monitor_state.hpp"

#include "common/dds/event_kinds.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdarg>
#include <cstdio>

#include "common/dds/experiment_text.hpp"

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

std::string num(double v) {
  if (!std::isfinite(v)) return "null";
  return fmt("%.6g", v);
}

std::string vec3(const std::array<double, 3>& v) {
  return "[" + num(v[0]) + ", " + num(v[1]) + ", " + num(v[2]) + "]";
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

std::string json_string(const std::string& s) {
  std::string o = "\"";
  for (const char c : s) {
    switch (c) {
      case '"':
        o += "\\\"";
        break;
      case '\\':
        o += "\\\\";
        break;
      case '\n':
        o += "\\n";
        break;
      case '\t':
        o += "\\t";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          o += fmt("\\u%04x", static_cast<unsigned>(static_cast<unsigned char>(c)));
        } else {
          o += c;
        }
    }
  }
  return o + "\"";
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

std::string experiment_json(const ExperimentDescription& e) {
  return "{\"session\": " + std::to_string(e.master_session()) +
         ", \"scheme\": " + json_string(e.scheme().to_string()) +
         ", \"master_stiffness_n_per_m\": " + num(e.master_stiffness_n_per_m()) +
         ", \"master_damping_ns_per_m\": " + num(e.master_damping_ns_per_m()) +
         ", \"force_gain\": " + num(e.force_gain()) +
         ", \"slave_stiffness_n_per_m\": " + num(e.slave_stiffness_n_per_m()) +
         ", \"forward_delay_ms\": " + num(e.forward_delay_ms()) +
         ", \"backward_delay_ms\": " + num(e.backward_delay_ms()) +
         ", \"forward_jitter_ms\": " + num(e.forward_jitter_ms()) +
         ", \"backward_jitter_ms\": " + num(e.backward_jitter_ms()) +
         ", \"forward_jitter_dist\": " + json_string(e.forward_jitter_dist().to_string()) +
         ", \"backward_jitter_dist\": " + json_string(e.backward_jitter_dist().to_string()) +
         ", \"forward_loss\": " + num(e.forward_loss()) +
         ", \"backward_loss\": " + num(e.backward_loss()) + ", \"forward_burst\": [" +
         num(e.forward_burst_p_gb()) + ", " + num(e.forward_burst_p_bg()) +
         "], \"backward_burst\": [" + num(e.backward_burst_p_gb()) + ", " +
         num(e.backward_burst_p_bg()) + "], \"seeds\": [" + std::to_string(e.forward_seed()) +
         ", " + std::to_string(e.backward_seed()) + "], \"rate_hz\": " + num(e.rate_hz()) +
         ", \"loop_delay_p50_ms\": " + num(e.loop_delay_p50_ms()) +
         ", \"loop_delay_p99_ms\": " + num(e.loop_delay_p99_ms()) +
         ", \"device\": " + json_string(e.device().to_string()) +
         ", \"driver_live\": " + (e.driver_live() ? "true" : "false") +
         ", \"driver_silences\": " + std::to_string(e.driver_silences()) +
         ", \"driver_silent_s\": " + num(e.driver_silent_s()) +
         ", \"driver_timeout_ms\": " + num(e.driver_timeout_ms()) + "}";
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

std::string render_json(const Snapshot& s) {
  std::string o = "{\"type\": \"status\", \"t\": " + num(s.t_s) +
                  ", \"domain\": " + std::to_string(s.domain) +
                  ", \"profile\": " + json_string(s.profile) +
                  ", \"insecure\": " + (s.insecure ? "true" : "false") +
                  ", \"full_rate\": " + (s.full_rate ? "true" : "false") +
                  ", \"waiting\": " + (s.waiting() ? "true" : "false") +
                  ", \"status\": " + json_string(s.status()) + ", \"topics\": {";
  bool first = true;
  for (const auto& t : s.topics) {
    o += (first ? "" : ", ") + json_string(t.name) + ": {\"count\": " + std::to_string(t.count) +
         ", \"rate_hz\": " + num(t.rate_hz) +
         ", \"age_s\": " + (t.seen() ? num(t.age_s) : std::string("null")) +
         ", \"stale\": " + (t.stale() ? "true" : "false") + "}";
    first = false;
  }
  o += "}";
  const TopicView* ts = s.topic("slave_state");
  if (s.have_slave && !(ts && ts->stale())) {
    o += ", \"slave\": {\"tip_m\": " + vec3(s.slave.tip_position_m()) +
         ", \"contact_force_n\": " + vec3(s.slave.contact_force_n()) +
         ", \"penetration_m\": " + num(s.slave.penetration_m()) +
         ", \"in_contact\": " + (s.slave.in_contact() ? "true" : "false") +
         ", \"holding\": " + (s.slave.holding() ? "true" : "false") + "}";
  } else {
    o += ", \"slave\": null";
  }
  const TopicView* tm = s.topic("master_state");
  if (s.have_master && !(tm && tm->stale())) {
    o += ", \"master\": {\"rtt_ms\": " + num(s.master.rtt_ms()) +
         ", \"rendered_force_n\": " + vec3(s.master.rendered_force_n()) +
         ", \"position_error_m\": " + num(s.master.position_error_m()) +
         ", \"link_ok\": " + (s.master.link_ok() ? "true" : "false") + "}";
  } else {
    o += ", \"master\": null";
  }
  const TopicView* tss = s.topic("server_stats");
  if (s.have_stats && !(tss && tss->stale())) {
    o += ", \"server\": {\"loop_rate_hz\": " + num(s.stats.loop_rate_hz()) +
         ", \"step_us_p50\": " + num(s.stats.step_us_p50()) +
         ", \"step_us_p99\": " + num(s.stats.step_us_p99()) +
         ", \"overruns\": " + std::to_string(s.stats.overruns()) +
         ", \"rejected\": " + std::to_string(rejected(s.stats)) +
         ", \"watchdog_trips\": " + std::to_string(s.stats.watchdog_trips()) +
         ", \"matched_state_readers\": " + std::to_string(s.stats.matched_state_readers()) + "}";
  } else {
    o += ", \"server\": null";
  }
  o += ", \"experiment\": " + (s.have_experiment ? experiment_json(s.experiment) : "null");
  return o + "}";
}

std::string event_json(const EventView& e) {
  return "{\"type\": \"event\", \"t\": " + num(e.at_s) +
         ", \"source\": " + json_string(e.event.source().to_string()) +
         ", \"kind\": " + json_string(dds::event_kind_name(e.event.kind())) +
         ", \"severity\": " + std::to_string(e.event.severity()) +
         ", \"message\": " + json_string(e.event.message().to_string()) +
         ", \"value\": " + num(e.event.value()) + "}";
}

std::string scene_json(const SceneDescription& d) {
  // each deformable body's automatic step: its stable step and the sub-steps it takes
  std::string deformables;
  for (const SceneObject& o : d.objects()) {
    if (o.kind() != OBJECT_DEFORMABLE_MESH) continue;
    deformables += std::string(deformables.empty() ? "" : ", ") +
                   "{\"id\": " + std::to_string(o.id()) +
                   ", \"highest_frequency_radps\": " + num(o.highest_frequency_radps()) +
                   ", \"stable_step_s\": " + num(o.stable_step_s()) +
                   ", \"substeps\": " + std::to_string(o.substeps()) + "}";
  }
  return "{\"type\": \"scene\", \"name\": " + json_string(d.name().to_string()) +
         ", \"objects\": " + std::to_string(d.objects().size()) +
         ", \"joints\": " + std::to_string(d.joint_count()) +
         ", \"physics_rate_hz\": " + num(d.physics_rate_hz()) +
         ", \"tip_radius_m\": " + num(d.tip_radius_m()) + ", \"deformables\": [" + deformables +
         "]}";
}

}  // namespace teleop::monitor
