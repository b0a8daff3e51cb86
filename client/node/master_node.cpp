#include "client/node/master_node.hpp"

#include <Eigen/Core>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <thread>

#include "client/node/rtt.hpp"
#include "common/dds/endpoint.hpp"
#include "common/util/clock.hpp"
#include "common/util/csv.hpp"
#include "common/util/rate_loop.hpp"
#include "common/util/signals.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::master {

namespace {

struct Target {
  Eigen::Vector3d p;
  Eigen::Vector3d v;
};

/// Scripted device motion in the slave frame (interim operator; the device layer replaces it).
Target scripted_target(const std::string& motion, double t) {
  const Eigen::Vector3d centre(0.6, 0.0, 0.35);
  constexpr double kPi = 3.14159265358979323846;
  if (motion == "circle") {
    const double r = 0.1, w = 2 * kPi * 0.25;
    return {centre + Eigen::Vector3d(r * std::cos(w * t), r * std::sin(w * t), 0.0),
            Eigen::Vector3d(-r * w * std::sin(w * t), r * w * std::cos(w * t), 0.0)};
  }
  if (motion == "press") {
    // down from z = 0.35 to 0.03 (tool radius 0.05: 20 mm into the floor) and back, 4 s period
    const double w = 2 * kPi * 0.25;
    const double mid = 0.19, amp = 0.16;
    return {Eigen::Vector3d(centre.x(), centre.y(), mid + amp * std::cos(w * t)),
            Eigen::Vector3d(0.0, 0.0, -amp * w * std::sin(w * t))};
  }
  return {centre, Eigen::Vector3d::Zero()};
}

std::string json_number(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

struct Received {
  SlaveState state;
  std::int64_t receive_ns = 0;
};

}  // namespace

struct MasterNode::Impl {
  MasterOptions options;
  dds::Participant participant;
  dds::Writer<MasterCommandPubSubType> command_writer;
  dds::Writer<MasterStatePubSubType> state_writer;
  dds::Writer<EventPubSubType> event_writer;
  dds::Mailbox<Received> mailbox;
  std::atomic<std::uint64_t> states_received{0};
  std::unique_ptr<dds::Reader<SlaveStatePubSubType>> state_reader;
  std::uint64_t event_seq = 0;

  explicit Impl(const MasterOptions& o)
      : options(o),
        participant(o.dds),
        command_writer(participant, dds::topics::kMasterCommand, dds::TopicQos::kStream),
        state_writer(participant, dds::topics::kMasterState, dds::TopicQos::kStream),
        event_writer(participant, dds::topics::kEvents, dds::TopicQos::kEventLog) {
    state_reader = std::make_unique<dds::Reader<SlaveStatePubSubType>>(
        participant, dds::topics::kSlaveState, dds::TopicQos::kStream,
        [this](const SlaveState& s, const eprosima::fastdds::dds::SampleInfo&) {
          states_received.fetch_add(1);
          mailbox.put(Received{s, now_ns()});
        });
  }

  void event(std::uint8_t kind, std::uint8_t severity, const std::string& msg, double value) {
    Event e;
    e.seq(++event_seq);
    e.time_ns(now_ns());
    e.source("master");
    e.kind(kind);
    e.severity(severity);
    e.message(msg);
    e.value(value);
    event_writer.write(e);
    if (!options.quiet) std::cerr << "teleop_master: " << msg << "\n";
  }

  int run() {
    install_stop_signal_handlers();
    // wait for the server: a matched command reader and a first SlaveState
    const std::int64_t wait_start = now_ns();
    while (!stop_requested()) {
      if (command_writer.matched() > 0 && mailbox.version() > 0) break;
      if (seconds_between(wait_start, now_ns()) > options.wait_server_s) {
        std::cerr << "teleop_master: no server answered on domain " << options.dds.domain
                  << " (profile " << options.dds.profile << ") within " << options.wait_server_s
                  << " s\n";
        return 3;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    const double wait_s = seconds_between(wait_start, now_ns());
    Received rx;
    std::uint64_t seen = 0;
    mailbox.take_if_newer(rx, seen);
    const std::uint64_t server_received_at_start = rx.state.commands_received();
    if (!options.quiet) {
      std::fprintf(stderr, "teleop_master: server found after %.3f s; running at %.0f Hz\n", wait_s,
                   options.rate_hz);
    }

    std::unique_ptr<CsvWriter> log;
    if (!options.log_csv.empty()) {
      log = std::make_unique<CsvWriter>(
          options.log_csv,
          std::vector<std::string>{"t_s", "seq", "xm_x", "xm_y", "xm_z", "xs_x", "xs_y", "xs_z",
                                   "fe_x", "fe_y", "fe_z", "fm_x", "fm_y", "fm_z", "rtt_ms",
                                   "link_ok", "in_contact"});
    }

    RateLoop loop(options.rate_hz);
    RttTracker rtt(1 << 20);
    MasterCommand cmd;
    MasterState ms;
    cmd.orientation_wxyz() = {1.0, 0.0, 0.0, 0.0};
    cmd.enabled(true);
    cmd.scheme(SCHEME_FORCE_POSITION);
    const std::int64_t t0 = now_ns();
    std::int64_t last_state_ns = rx.receive_ns;
    bool link_ok = true;
    double fade = 1.0;
    std::uint64_t link_losses = 0;
    std::uint64_t seq = 0;
    double last_rtt = std::nan("");
    const auto state_every = std::max<std::uint64_t>(
        1, static_cast<std::uint64_t>(std::llround(options.rate_hz / options.state_rate_hz)));
    Eigen::Vector3d fe = Eigen::Vector3d::Zero();
    Eigen::Vector3d xs(rx.state.tip_position_m()[0], rx.state.tip_position_m()[1],
                       rx.state.tip_position_m()[2]);
    bool in_contact = false;
    const double dt = 1.0 / options.rate_hz;

    while (!stop_requested()) {
      const std::int64_t now = now_ns();
      const double t = seconds_between(t0, now);
      if (options.duration_s > 0 && t >= options.duration_s) break;
      if (options.samples > 0 && seq >= options.samples) break;

      // device (scripted) -> command
      const Target target = scripted_target(options.motion, t);
      cmd.seq(++seq);
      cmd.send_time_ns(now_ns());
      cmd.position_m() = {target.p.x(), target.p.y(), target.p.z()};
      cmd.linear_velocity_mps() = {target.v.x(), target.v.y(), target.v.z()};
      command_writer.write(cmd);

      // newest slave state
      if (mailbox.take_if_newer(rx, seen)) {
        last_state_ns = rx.receive_ns;
        const double r = rtt.on_echo(rx.state.command_seq(), rx.state.command_send_time_ns(),
                                     rx.receive_ns, seq);
        if (r >= 0) last_rtt = r;
        const auto& f = rx.state.contact_force_n();
        fe = Eigen::Vector3d(f[0], f[1], f[2]);
        const auto& p = rx.state.tip_position_m();
        xs = Eigen::Vector3d(p[0], p[1], p[2]);
        in_contact = rx.state.in_contact();
      }
      // link watchdog: fade the force to zero when SlaveState stops arriving
      const bool ok = seconds_between(last_state_ns, now_ns()) <= options.link_timeout_s;
      if (ok != link_ok) {
        link_ok = ok;
        if (!ok) {
          ++link_losses;
          event(EVENT_SAFETY, 1, "no SlaveState within the link timeout: fading force to zero",
                options.link_timeout_s * 1e3);
        } else {
          event(EVENT_SAFETY, 0, "SlaveState arriving again: force restored", 0.0);
        }
      }
      const double fade_rate = options.force_fade_s > 0 ? dt / options.force_fade_s : 1.0;
      fade = link_ok ? std::min(1.0, fade + fade_rate) : std::max(0.0, fade - fade_rate);
      Eigen::Vector3d fm = fade * options.force_scale * fe;
      const double fn = fm.norm();
      if (fn > options.max_force_n) fm *= options.max_force_n / fn;

      if (seq % state_every == 0) {
        ms.seq(seq);
        ms.time_ns(now_ns());
        ms.device_position_m() = cmd.position_m();
        ms.device_orientation_wxyz() = cmd.orientation_wxyz();
        ms.device_velocity_mps() = cmd.linear_velocity_mps();
        ms.rendered_force_n() = {fm.x(), fm.y(), fm.z()};
        ms.environment_force_n() = {fe.x(), fe.y(), fe.z()};
        ms.position_error_m((target.p - xs).norm());
        ms.rtt_ms(last_rtt);
        ms.mode(cmd.scheme());
        ms.link_ok(link_ok);
        state_writer.write(ms);
      }
      if (log) {
        log->row({t, static_cast<double>(seq), target.p.x(), target.p.y(), target.p.z(), xs.x(),
                  xs.y(), xs.z(), fe.x(), fe.y(), fe.z(), fm.x(), fm.y(), fm.z(), last_rtt,
                  link_ok ? 1.0 : 0.0, in_contact ? 1.0 : 0.0});
      }
      loop.wait();
    }
    const double elapsed = seconds_between(t0, now_ns());
    // drain: late echoes and the server's final receive count
    const std::int64_t drain_start = now_ns();
    while (seconds_between(drain_start, now_ns()) < options.drain_s) {
      if (mailbox.take_if_newer(rx, seen)) {
        rtt.on_echo(rx.state.command_seq(), rx.state.command_send_time_ns(), rx.receive_ns, seq);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    state_reader->stop();

    const std::uint64_t sent = seq;
    const std::uint64_t server_received =
        rx.state.commands_received() >= server_received_at_start
            ? rx.state.commands_received() - server_received_at_start
            : 0;
    const std::uint64_t received = std::min(server_received, sent);
    const Summary r = summarize(rtt.rtt_ms().snapshot());
    const Summary j = summarize(loop.lateness_us().snapshot());
    if (!options.summary_json.empty()) {
      std::ofstream f(options.summary_json);
      f << "{\n"
        << "  \"duration_s\": " << json_number(elapsed) << ",\n"
        << "  \"rate_hz\": " << json_number(options.rate_hz) << ",\n"
        << "  \"sent\": " << sent << ",\n"
        << "  \"received\": " << received << ",\n"
        << "  \"lost\": " << (sent - received) << ",\n"
        << "  \"echoed\": " << rtt.unique_echoes() << ",\n"
        << "  \"states_received\": " << states_received.load() << ",\n"
        << "  \"rtt_ms\": {\"p50\": " << json_number(r.p50) << ", \"p90\": " << json_number(r.p90)
        << ", \"p99\": " << json_number(r.p99) << ", \"p999\": " << json_number(r.p999)
        << ", \"max\": " << json_number(r.max) << ", \"mean\": " << json_number(r.mean)
        << ", \"count\": " << r.count << "},\n"
        << "  \"loop_jitter_us\": {\"p50\": " << json_number(j.p50)
        << ", \"p99\": " << json_number(j.p99) << ", \"max\": " << json_number(j.max) << "},\n"
        << "  \"overruns\": " << loop.overruns() << ",\n"
        << "  \"link_losses\": " << link_losses << ",\n"
        << "  \"wait_server_s\": " << json_number(wait_s) << "\n"
        << "}\n";
    }
    if (!options.quiet) {
      std::fprintf(
          stdout,
          "session summary\n"
          "  duration        %.2f s at %.0f Hz\n"
          "  commands        %llu sent, %llu received by the server, %llu lost "
          "(%.2f%%)\n"
          "  round trip      p50 %.3f ms  p99 %.3f ms  max %.3f ms  (%zu echoes)\n"
          "  loop jitter     p50 %.1f us  p99 %.1f us  (%llu overruns)\n"
          "  link losses     %llu\n",
          elapsed, options.rate_hz, static_cast<unsigned long long>(sent),
          static_cast<unsigned long long>(received),
          static_cast<unsigned long long>(sent - received),
          sent ? 100.0 * static_cast<double>(sent - received) / static_cast<double>(sent) : 0.0,
          r.p50, r.p99, r.max, r.count, j.p50, j.p99,
          static_cast<unsigned long long>(loop.overruns()),
          static_cast<unsigned long long>(link_losses));
    }
    return 0;
  }
};

MasterNode::MasterNode(const MasterOptions& options) : impl_(std::make_unique<Impl>(options)) {}
MasterNode::~MasterNode() = default;
int MasterNode::run() { return impl_->run(); }

}  // namespace teleop::master
