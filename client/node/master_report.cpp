#include "client/node/master_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include "common/util/exit_codes.hpp"
#include "common/util/files.hpp"
#include "common/util/version.hpp"

namespace teleop::master {

namespace {

/// A log row; the count must match the header exactly (checked at compile time).
template <class... T>
std::array<double, CycleLog::kColumns> csv_row(T... v) {
  static_assert(sizeof...(T) == CycleLog::kColumns, "log row and header differ in length");
  return {static_cast<double>(v)...};
}

/// Force error RMS relative to the mean contact force (NaN without contact).
double relative_force_error(const SessionMetrics& m) {
  const double f = m.mean_contact_force_n();
  return f > 1e-9 ? m.force_error_rms_n() / f : std::nan("");
}

using ull = unsigned long long;

// ---- the JSON summary ----

/// The summary's counts of the command link, the server's and the network threads'.
void add_link_fields(OrderedJson& out, const SessionReport& rep, const ServerBinding& binding) {
  out["issued"] = rep.issued;
  out["dropped_by_channel"] = rep.dropped;
  out["sent"] = rep.sent;
  out["received"] = rep.received;
  out["in_flight"] = rep.in_flight;
  out["lost"] = lost_commands(link_counts(rep));
  out["server"] = {{"faults", rep.server_faults},     {"watchdog_trips", rep.server_watchdog_trips},
                   {"overruns", rep.server_overruns}, {"rejected", rep.server_rejected},
                   {"restarts", rep.server_restarts}, {"gain_clamped", rep.server_gain_clamp}};
  // which server this master believed, and what it ignored from other participants
  out["server_binding"] = {{"server", binding.server()},
                           {"bound", binding.bound()},
                           {"rebinds", binding.rebinds()},
                           {"foreign",
                            {{"states", binding.foreign(ServerBinding::kState)},
                             {"stats", binding.foreign(ServerBinding::kStats)},
                             {"events", binding.foreign(ServerBinding::kEvent)}}},
                           {"first_foreign", binding.first_foreign()}};
  out["network_threads"] = {{"commands_dropped", rep.commands_dropped},
                            {"command_write_failures", rep.command_write_failures},
                            {"states_replaced", rep.states_replaced},
                            {"events_dropped", rep.events_dropped},
                            {"write_failures", rep.write_failures}};
}

/// The summary's round trip, loop delay and jitter, overruns, link losses and stalls.
void add_timing_fields(OrderedJson& out, const SessionReport& rep) {
  const Summary& r = rep.rtt_ms;
  const Summary& ld = rep.loop_delay_ms;
  const Summary& j = rep.jitter_us;
  out["rtt_ms"] = {{"p50", json_number(r.p50)}, {"p90", json_number(r.p90)},
                   {"p99", json_number(r.p99)}, {"p999", json_number(r.p999)},
                   {"max", json_number(r.max)}, {"mean", json_number(r.mean)},
                   {"count", r.count}};
  out["loop_delay_ms"] = {{"p50", json_number(ld.p50)},
                          {"p99", json_number(ld.p99)},
                          {"max", json_number(ld.max)},
                          {"count", ld.count}};
  out["loop_jitter_us"] = {
      {"p50", json_number(j.p50)}, {"p99", json_number(j.p99)}, {"max", json_number(j.max)}};
  out["overruns"] = rep.overruns;
  out["closing_cycles"] = rep.closing_cycles;
  out["releases_sent"] = rep.releases_sent;
  out["link_losses"] = rep.link_losses;
  out["stalls"] = {{"count", rep.stalls}, {"longest_s", json_number(rep.longest_stall_s)}};
  out["wait_server_s"] = json_number(rep.wait_s);
}

/// The summary's safety layer, re-homes and device driver.
void add_safety_fields(OrderedJson& out, const MasterCycle& cycle, const SessionReport& rep,
                       double driver_timeout_s) {
  const SafetyLayer& safety = cycle.safety();
  out["safety"] = {
      {"cut", safety.cut()},
      {"reason", safety.cut_reason()},
      {"max_output_n", json_number(safety.max_output_n())},
      {"max_step_n", json_number(safety.max_step_n())},
      {"max_force_rate_n_per_s", json_number(cycle.device_spec().max_force_rate_n_per_s)},
      {"rate_limited_cycles", safety.rate_limited_cycles()},
      {"workspace_violations", cycle.workspace_violations()}};
  out["rehomes"] = {{"total", cycle.rehomes()},
                    {"link_back", cycle.rehomes(RehomeReason::kLinkBack)},
                    {"slave_restart", cycle.rehomes(RehomeReason::kSlaveRestart)},
                    {"takeover", cycle.rehomes(RehomeReason::kTakeover)},
                    {"driver_back", cycle.rehomes(RehomeReason::kDriverBack)}};
  out["driver"] = {{"timeout_ms", json_number(driver_timeout_s * 1e3)},
                   {"silences", rep.driver_silences},
                   {"silent_s", json_number(rep.driver_silent_s)},
                   {"live_s", json_number(std::max(0.0, rep.session_s - rep.driver_silent_s))},
                   {"figures", "over the time the device was live"}};
}

/// {"accepting":..,"received":..,"applied":..,"rejected":..,"ignored":..,"dropped":..,
///  "in_force": {...}}: live tuning over the session.
OrderedJson tuning_fields(const MasterCycle& cycle, const TuningCounts& tuning) {
  const TuningValues& v = cycle.tuning().current();
  OrderedJson in_force = {{"master_stiffness_n_per_m", json_number(v.master_stiffness_n_per_m)},
                          {"master_damping_ns_per_m", json_number(v.master_damping_ns_per_m)},
                          {"force_gain", json_number(v.force_gain)},
                          {"slave_stiffness_n_per_m", json_number(v.slave_stiffness_n_per_m)},
                          {"forward_delay_ms", json_number(v.forward_delay_s * 1e3)},
                          {"backward_delay_ms", json_number(v.backward_delay_s * 1e3)}};
  return {{"accepting", tuning.accepting},       {"received", tuning.received},
          {"applied", cycle.tunings_accepted()}, {"rejected", cycle.tunings_rejected()},
          {"ignored", tuning.ignored},           {"dropped", tuning.dropped},
          {"in_force", std::move(in_force)}};
}

OrderedJson hertz_fields(const HertzReference& hz) {
  return {{"valid", hz.valid},
          {"travel_m", json_number(hz.travel_m)},
          {"force_n", json_number(hz.force_n)},
          {"tangent_n_per_m", json_number(hz.tangent_n_per_m)},
          {"secant_n_per_m", json_number(hz.secant_n_per_m)},
          {"fit_from_m", json_number(hz.fit_from_m)},
          {"fit_to_m", json_number(hz.fit_to_m)},
          {"fit_n_per_m", json_number(hz.fit_n_per_m)}};
}

// ---- the printout ----

/// "session summary (...)" and the lines of the link and the loop's timing.
std::string link_lines(const MasterCycle& cycle, const SessionReport& rep,
                       const MasterOptions& options) {
  const ChannelReport& fwd = rep.forward;
  const ChannelReport& bwd = rep.backward;
  const Summary& r = rep.rtt_ms;
  const Summary& ld = rep.loop_delay_ms;
  const Summary& j = rep.jitter_us;
  const std::uint64_t lost = lost_commands(link_counts(rep));
  const std::uint64_t left = rep.issued - rep.in_flight;
  char text[4096];
  std::snprintf(
      text, sizeof(text),
      "session summary (%s, %s, script %s)\n"
      "  duration        %.2f s (%.2f s of session after homing) at %.0f Hz\n"
      "  commands        %llu issued, %llu received by the server, %llu lost (%.2f%%; "
      "%llu dropped by the injected channel, %llu sent), %llu in flight at the end\n"
      "  injected delay  forward %s; measured mean %.2f ms, p99 %.2f ms, lost %.2f%%\n"
      "                  backward %s; measured mean %.2f ms, p99 %.2f ms, lost %.2f%%\n"
      "  round trip      p50 %.3f ms  p99 %.3f ms  max %.3f ms  (%zu echoes, network)\n"
      "  loop delay      p50 %.3f ms  p99 %.3f ms  (command in -> its echo used)\n"
      "  loop jitter     p50 %.1f us  p99 %.1f us  (%llu overruns)\n",
      cycle.config().controller.scheme.c_str(), options.device.c_str(), options.script.c_str(),
      rep.elapsed_s, rep.session_s, options.rate_hz, static_cast<ull>(rep.issued),
      static_cast<ull>(rep.received), static_cast<ull>(lost),
      left ? 100.0 * static_cast<double>(lost) / static_cast<double>(left) : 0.0,
      static_cast<ull>(rep.dropped), static_cast<ull>(rep.sent), static_cast<ull>(rep.in_flight),
      options.forward.describe().c_str(), fwd.delay_mean_ms, fwd.delay_p99_ms,
      100.0 * fwd.loss_fraction, options.backward.describe().c_str(), bwd.delay_mean_ms,
      bwd.delay_p99_ms, 100.0 * bwd.loss_fraction, r.p50, r.p99, r.max, r.count, ld.p50, ld.p99,
      j.p50, j.p99, static_cast<ull>(rep.overruns));
  return text;
}

/// The lines of tracking, force and transparency, and the Hertz reference's.
std::string contact_lines(const SessionMetrics& metrics, const SessionReport& rep,
                          const SceneDescription& scene) {
  const double rel = relative_force_error(metrics);
  char rel_buf[32];
  std::snprintf(rel_buf, sizeof(rel_buf), "%.0f%%", 100.0 * rel);
  const std::string relative = std::isfinite(rel) ? rel_buf : "no contact: -";
  char text[4096];
  std::snprintf(
      text, sizeof(text),
      "  tracking        position error RMS %.2f mm, max %.2f mm\n"
      "  force           max rendered %.2f N, force error RMS %.3f N (%s of the mean "
      "contact force), contact %.2f s, mean contact force %.2f N\n"
      "  transparency    over the %.2f s the device was live: free space %.3f N mean, %.3f N "
      "p99, %.3f N max; in contact felt %.2f x "
      "the environment's force (RMS %.3f N), stiffness felt %.0f N/m against %.0f N/m (%.2f; "
      "loading fit F = k x + b, b %.2f N against %.2f N)\n"
      "%s",
      metrics.position_error_rms_m() * 1e3, metrics.position_error_max_m() * 1e3,
      metrics.max_device_force_n(), metrics.force_error_rms_n(), relative.c_str(),
      metrics.contact_time_s(), metrics.mean_contact_force_n(),
      std::max(0.0, rep.session_s - rep.driver_silent_s), metrics.free_force_mean_n(),
      metrics.free_force_p99_n(), metrics.free_force_max_n(), metrics.felt_force_ratio(),
      metrics.felt_force_error_rms_n(), metrics.felt_stiffness_n_per_m(),
      metrics.environment_stiffness_n_per_m(), metrics.stiffness_ratio(),
      metrics.felt_fit().offset(), metrics.environment_fit().offset(),
      hertz_line(hertz_for_session(scene, metrics), metrics.felt_stiffness_n_per_m(),
                 metrics.environment_stiffness_n_per_m())
          .c_str());
  return text;
}

/// The ownership line's text: which session this master was and whether it had the slave.
std::string ownership_text(const SessionReport& rep, std::uint32_t master_session) {
  char own_buf[160];
  std::snprintf(own_buf, sizeof(own_buf), "session 0x%08x%s", master_session,
                rep.refused ? ": REFUSED, another master owns the slave"
                            : (rep.issued_before_owning > 0 ? ": got the slave after waiting"
                                                            : ": owned the slave"));
  std::string ownership = own_buf;
  if (rep.issued_before_owning > 0 || rep.refused) {
    ownership += " (" + std::to_string(rep.issued_before_owning) +
                 " commands sent while refused, " + std::to_string(rep.waited_for_owner_s) + " s)";
  }
  return ownership;
}

/// The lines of passivity, safety and ownership.
std::string safety_lines(const MasterCycle& cycle, const SessionReport& rep,
                         std::uint32_t master_session) {
  const SessionMetrics& metrics = cycle.metrics();
  const SafetyLayer& safety = cycle.safety();
  const std::string ownership = ownership_text(rep, master_session);
  char text[2048];
  std::snprintf(
      text, sizeof(text),
      "  passivity       energy at the master port %.4f J (min %.4f J)\n"
      "  safety          %s%s, link losses %llu, loop stalls %llu (longest %.3f s), re-homed "
      "%llu times (link back %llu, slave "
      "restart %llu, takeover %llu); force change at most %.3f N per cycle (bound %.0f N/s, "
      "held to it in %llu cycles)\n"
      "  ownership       %s\n",
      metrics.energy_j(), metrics.energy_min_j(), safety.cut() ? "CUT: " : "ok",
      safety.cut() ? safety.cut_reason() : "", static_cast<ull>(rep.link_losses),
      static_cast<ull>(rep.stalls), rep.longest_stall_s, static_cast<ull>(cycle.rehomes()),
      static_cast<ull>(cycle.rehomes(RehomeReason::kLinkBack)),
      static_cast<ull>(cycle.rehomes(RehomeReason::kSlaveRestart)),
      static_cast<ull>(cycle.rehomes(RehomeReason::kTakeover)), safety.max_step_n(),
      cycle.device_spec().max_force_rate_n_per_s, static_cast<ull>(safety.rate_limited_cycles()),
      ownership.c_str());
  return text;
}

/// The tuning line (only when the master accepts tuning requests).
std::string tuning_line(const MasterCycle& cycle, const TuningCounts& tuning) {
  if (!tuning.accepting) return "";
  const TuningValues& v = cycle.tuning().current();
  char buf[256];
  std::snprintf(buf, sizeof(buf),
                "  tuning          %llu requests: %llu applied, %llu rejected; in force K_pm "
                "%.0f N/m, B_m %.2f N s/m, K_f %.2f, K_ps %.0f N/m, delay %.1f / %.1f ms\n",
                static_cast<ull>(tuning.received), static_cast<ull>(cycle.tunings_accepted()),
                static_cast<ull>(cycle.tunings_rejected()), v.master_stiffness_n_per_m,
                v.master_damping_ns_per_m, v.force_gain, v.slave_stiffness_n_per_m,
                v.forward_delay_s * 1e3, v.backward_delay_s * 1e3);
  return buf;
}

/// The lines on the server binding and the loop's network threads.
std::string binding_lines(const SessionReport& rep, const ReportContext& ctx) {
  const ServerBinding& binding = ctx.binding;
  char buf[512];
  std::snprintf(
      buf, sizeof(buf),
      "  server binding  %s %s (%llu moves); ignored from other participants: %llu states, "
      "%llu stats, %llu server events%s%s\n"
      "  network thread  commands: %llu replaced by a newer one, %llu refused; states: %llu "
      "replaced; events: %llu dropped; other writes refused: %llu\n",
      binding.bound() ? "bound to" : "never bound, followed", binding.server().c_str(),
      static_cast<ull>(binding.rebinds()), static_cast<ull>(binding.foreign(ServerBinding::kState)),
      static_cast<ull>(binding.foreign(ServerBinding::kStats)),
      static_cast<ull>(binding.foreign(ServerBinding::kEvent)),
      binding.foreign_total() > 0 ? " (first from " : "",
      binding.foreign_total() > 0 ? (binding.first_foreign() + ")").c_str() : "",
      static_cast<ull>(rep.commands_dropped), static_cast<ull>(rep.command_write_failures),
      static_cast<ull>(rep.states_replaced), static_cast<ull>(rep.events_dropped),
      static_cast<ull>(rep.write_failures));
  std::string lines = buf;
  if (ctx.options.device == "external") {
    // teleop/device_state: one driver at a time
    lines += "  device driver   " + std::to_string(ctx.device_samples_ignored) +
             " teleop/device_state samples of a second driver ignored\n";
  }
  return lines;
}

/// The line on the device's silences (MasterCycle::check_driver).
std::string driver_line(const MasterCycle& cycle, const SessionReport& rep,
                        double driver_timeout_s) {
  char buf[400];
  if (rep.driver_silences == 0) {
    std::snprintf(buf, sizeof(buf),
                  "  device          live the whole session (never without a valid reading "
                  "for over %.0f ms)\n",
                  driver_timeout_s * 1e3);
    return buf;
  }
  std::snprintf(buf, sizeof(buf),
                "  device          live %.2f s of %.2f s; silent %llu times, %.2f s in all (no "
                "valid reading for over %.0f ms: the slave held, the force faded; not in the "
                "figures), came back %llu times\n",
                std::max(0.0, rep.session_s - rep.driver_silent_s), rep.session_s,
                static_cast<ull>(rep.driver_silences), rep.driver_silent_s, driver_timeout_s * 1e3,
                static_cast<ull>(cycle.rehomes(RehomeReason::kDriverBack)));
  return buf;
}

/// The lines of the server's counts and the verdict.
std::string server_lines(const MasterCycle& cycle, const SessionReport& rep) {
  const SessionVerdict verdict =
      session_verdict(cycle.metrics(), rep, cycle.config().controller.scheme);
  const std::string& reason = verdict.reason;
  char text[2048];
  std::snprintf(text, sizeof(text),
                "  server          %llu faults, %llu watchdog trips, %llu overruns, %llu commands "
                "rejected, %llu restarts\n"
                "  verdict         %s%s%s\n",
                static_cast<ull>(rep.server_faults), static_cast<ull>(rep.server_watchdog_trips),
                static_cast<ull>(rep.server_overruns), static_cast<ull>(rep.server_rejected),
                static_cast<ull>(rep.server_restarts), verdict.name.c_str(),
                reason.empty() ? "" : " - ", reason.c_str());
  if (rep.server_gain_clamp.empty()) return text;
  return "  slave gain      " + rep.server_gain_clamp + "\n" + text;
}

}  // namespace

LinkCounts link_counts(const SessionReport& rep) {
  LinkCounts counts;
  counts.issued = rep.issued;
  counts.in_flight = rep.in_flight;
  counts.received = rep.received;
  counts.rejected = rep.server_rejected;
  counts.rtt_p99_ms = rep.rtt_ms.p99;
  counts.echoes = rep.rtt_ms.count;
  counts.driver_silences = rep.driver_silences;
  counts.driver_silent_s = rep.driver_silent_s;
  return counts;
}

SessionVerdict session_verdict(const SessionMetrics& m, const SessionReport& rep,
                               const std::string& scheme) {
  if (rep.refused && rep.issued == 0) {
    return SessionVerdict{"refused", "another master owns the slave", exit_code::kRefused};
  }
  return combine_verdict(m.verdict(), m.verdict_reason(),
                         judge_link(link_counts(rep), link_tolerance(scheme)));
}

HertzReference hertz_for_session(const SceneDescription& scene, const SessionMetrics& metrics) {
  double gravity = 0.0;
  for (double g : scene.gravity_mps2()) gravity += g * g;
  gravity = std::sqrt(gravity);
  for (const SceneObject& o : scene.objects()) {
    if (o.kind() != OBJECT_DEFORMABLE_MESH || !(o.youngs_modulus_pa() > 0.0)) continue;
    const LoadingFit& fit = metrics.environment_fit();
    const bool fitted = std::isfinite(metrics.environment_stiffness_n_per_m());
    return hertz_reference(o.youngs_modulus_pa(), o.poisson_ratio(), o.size_m()[0],
                           scene.tip_radius_m(), o.mass_kg() * gravity, metrics.max_slave_depth_m(),
                           fitted ? fit.x_min : 0.0, fitted ? fit.x_max : 0.0);
  }
  return HertzReference{};
}

OrderedJson session_summary_json(const MasterCycle& cycle, const SessionReport& rep,
                                 const ReportContext& ctx) {
  const MasterOptions& options = ctx.options;
  const SessionMetrics& metrics = cycle.metrics();
  const SessionVerdict verdict = session_verdict(metrics, rep, cycle.config().controller.scheme);
  OrderedJson out;
  out["version"] = version_string();
  out["hertz"] = hertz_fields(hertz_for_session(ctx.scene, metrics));
  out["duration_s"] = json_number(rep.elapsed_s);
  out["session_s"] = json_number(rep.session_s);
  out["rate_hz"] = json_number(options.rate_hz);
  out["scheme"] = cycle.config().controller.scheme;
  out["device"] = options.device;
  out["device_samples_ignored"] = ctx.device_samples_ignored;
  out["script"] = options.script;
  add_link_fields(out, rep, ctx.binding);
  out["force_error_relative"] = json_number(relative_force_error(metrics));
  out["echoed"] = rep.echoed;
  out["states_received"] = rep.states_received;
  add_timing_fields(out, rep);
  out["insecure"] = options.dds.insecure;
  out["verdict"] = verdict.name;
  out["verdict_reason"] = verdict.reason;
  out["metrics"] = metrics.summary_fields();
  out["transparency"] = metrics.transparency_fields();
  out["delay"] = {{"forward", channel_fields(rep.forward)},
                  {"backward", channel_fields(rep.backward)}};
  add_safety_fields(out, cycle, rep, options.driver_timeout_s);
  out["experiment_writes"] = rep.experiment_writes;
  out["tuning"] = tuning_fields(cycle, ctx.tuning);
  out["ownership"] = {{"session", ctx.master_session},
                      {"refused", rep.refused},
                      {"issued_before_owning", rep.issued_before_owning},
                      {"waited_s", json_number(rep.waited_for_owner_s)},
                      {"server_says", rep.owner_message}};
  return out;
}

void write_session_summary_json(const std::string& path, const MasterCycle& cycle,
                                const SessionReport& rep, const ReportContext& ctx) {
  write_text_file(path, json_document(session_summary_json(cycle, rep, ctx)));
}

std::string session_summary_text(const MasterCycle& cycle, const SessionReport& rep,
                                 const ReportContext& ctx) {
  const double driver_timeout_s = ctx.options.driver_timeout_s;
  return nan_as_na(link_lines(cycle, rep, ctx.options) +
                   contact_lines(cycle.metrics(), rep, ctx.scene) +
                   safety_lines(cycle, rep, ctx.master_session) + tuning_line(cycle, ctx.tuning) +
                   binding_lines(rep, ctx) + driver_line(cycle, rep, driver_timeout_s) +
                   server_lines(cycle, rep));
}

CycleLog::CycleLog(const std::string& path, double delay_injected_ms)
    : csv_(
          path,
          std::vector<std::string>{
              "t_s", "phase", "seq", "xm_x", "xm_y", "xm_z", "xs_x", "xs_y", "xs_z", "fe_x", "fe_y",
              "fe_z", "fm_x", "fm_y", "fm_z", "rtt_ms", "link_ok", "in_contact", "penetration_m",
              "energy_j", "safety_scale", "position_error_m", "deformation_m", "loop_delay_ms",
              "delay_injected_ms", "passivity_observer_j", "passivity_dissipated_j",
              // the device's own pose: the log is a --device replay file
              "dev_x", "dev_y", "dev_z", "dev_qw", "dev_qx", "dev_qy", "dev_qz",
              // the samples of the summary's stiffness fits (docs/control.md, "Transparency")
              "slave_depth_m", "master_depth_m", "felt_force_n", "loading"}),
      delay_injected_ms_(delay_injected_ms) {}

void CycleLog::row(const MasterCycle& cycle, double t_s, double rtt_ms, double loop_delay_ms) {
  const MetricsSample& m = cycle.last_sample();
  const SlaveSample& xs = cycle.slave_at_master();
  const BilateralController::PassivityStatus ps = cycle.controller().passivity_status();
  const Eigen::Vector3d& xm = m.master_position_m;
  const Eigen::Vector3d& fe = xs.contact_force_n;
  const Eigen::Vector3d& f = cycle.device_force_n();
  const DeviceReading& dev = cycle.reading();
  const auto vals = csv_row(
      t_s, cycle.homing_cycle() ? 0.0 : 1.0, static_cast<double>(cycle.command_seq()), xm.x(),
      xm.y(), xm.z(), xs.position_m.x(), xs.position_m.y(), xs.position_m.z(), fe.x(), fe.y(),
      fe.z(), f.x(), f.y(), f.z(), rtt_ms, cycle.safety().link_lost() ? 0.0 : 1.0,
      xs.in_contact ? 1.0 : 0.0, xs.penetration_m, cycle.metrics().energy_j(),
      cycle.safety().scale(), (xm - xs.position_m).norm(), xs.deformation_m, loop_delay_ms,
      delay_injected_ms_, ps.observer_j, ps.dissipated_j, dev.position_m.x(), dev.position_m.y(),
      dev.position_m.z(), dev.orientation.w(), dev.orientation.x(), dev.orientation.y(),
      dev.orientation.z(), m.slave_depth_m, m.master_depth_m, m.felt_force_n,
      static_cast<double>(cycle.metrics().last_sample_loading()));
  csv_.row(vals.data(), vals.size());
}

}  // namespace teleop::master
