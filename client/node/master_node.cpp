#include "client/node/master_node.hpp"

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <thread>

#include "client/control/loopback_session.hpp"
#include "client/device/device_factory.hpp"
#include "client/device/device_idl.hpp"
#include "client/device/external_device.hpp"
#include "client/device/replay_device.hpp"
#include "client/device/simulated_device.hpp"
#include "client/metrics/session_metrics.hpp"
#include "client/net/delay_channel.hpp"
#include "client/node/rtt.hpp"
#include "common/dds/endpoint.hpp"
#include "common/dds/rate_limited_publisher.hpp"
#include "common/dds/teleop_idl.hpp"
#include "common/util/clock.hpp"
#include "common/util/csv.hpp"
#include "common/util/rate_loop.hpp"
#include "common/util/signals.hpp"
#include "teleop/idl/DevicePubSubTypes.h"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::master {

namespace {

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

/// Minimum-jerk blend s(t) in [0, 1] for t in [0, T].
double min_jerk(double t, double T) {
  if (T <= 0.0 || t >= T) return 1.0;
  if (t <= 0.0) return 0.0;
  const double u = t / T;
  return u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
}

constexpr std::size_t kCsvColumns = 27;
/// A log row; the count must match the header exactly (checked at compile time).
template <class... T>
std::array<double, kCsvColumns> csv_row(T... v) {
  static_assert(sizeof...(T) == kCsvColumns, "log row and header differ in length");
  return {static_cast<double>(v)...};
}
/// Commands whose entry time is remembered for the loop-delay measurement.
constexpr std::uint64_t kEntryRing = 1 << 16;

}  // namespace

struct MasterNode::Impl {
  MasterOptions options;
  dds::Participant participant;
  dds::Writer<MasterCommandPubSubType> command_writer;
  dds::Writer<MasterStatePubSubType> state_writer;
  dds::Writer<EventPubSubType> event_writer;
  // observers' rate-limited copies of MasterState, written from their own thread: the haptic
  // loop's cost does not grow with the number of observers (docs/topics.md)
  dds::RateLimitedPublisher<MasterStatePubSubType> state_views;
  dds::Mailbox<Received> mailbox;
  dds::Mailbox<SceneDescription> scene_box;
  std::atomic<std::uint64_t> states_received{0};
  std::unique_ptr<dds::Reader<SlaveStatePubSubType>> state_reader;
  std::unique_ptr<dds::Reader<SceneDescriptionPubSubType>> scene_reader;
  // external device transport (only with --device external)
  std::unique_ptr<dds::Writer<DeviceCommandPubSubType>> device_command_writer;
  std::unique_ptr<dds::Reader<DeviceStatePubSubType>> device_state_reader;
  dds::Mailbox<DeviceState> device_box;
  std::uint64_t event_seq = 0;

  explicit Impl(const MasterOptions& o)
      : options(o),
        participant(o.dds),
        command_writer(participant, dds::topics::kMasterCommand, dds::TopicQos::kStream),
        state_writer(participant, dds::topics::kMasterState, dds::TopicQos::kStream),
        event_writer(participant, dds::topics::kEvents, dds::TopicQos::kEventLog),
        state_views(participant,
                    {{dds::topics::kMasterStateView, dds::topics::kViewRateHz},
                     {dds::topics::kMasterStateMonitor, dds::topics::kMonitorRateHz}}) {
    state_reader = std::make_unique<dds::Reader<SlaveStatePubSubType>>(
        participant, dds::topics::kSlaveState, dds::TopicQos::kStream,
        [this](const SlaveState& s, const eprosima::fastdds::dds::SampleInfo&) {
          states_received.fetch_add(1);
          mailbox.put(Received{s, now_ns()});
        });
    scene_reader = std::make_unique<dds::Reader<SceneDescriptionPubSubType>>(
        participant, dds::topics::kScene, dds::TopicQos::kLatched,
        [this](const SceneDescription& s, const eprosima::fastdds::dds::SampleInfo&) {
          scene_box.put(s);
        });
    if (o.device == "external") {
      device_command_writer = std::make_unique<dds::Writer<DeviceCommandPubSubType>>(
          participant, "teleop/device_command", dds::TopicQos::kStream);
      device_state_reader = std::make_unique<dds::Reader<DeviceStatePubSubType>>(
          participant, "teleop/device_state", dds::TopicQos::kStream,
          [this](const DeviceState& s, const eprosima::fastdds::dds::SampleInfo&) {
            device_box.put(s);
          });
    }
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
    if (!options.quiet && severity > 0) std::cerr << "teleop_master: " << msg << "\n";
  }

  /// Where the master's origin lands in the slave world: the point where the tip centre is
  /// when its surface just touches the target surface (top of the first deformable body, else
  /// the floor under the tip).
  Eigen::Vector3d contact_point(const SceneDescription* scene, const Eigen::Vector3d& tip) {
    if (options.has_contact_point) return options.contact_point_m;
    const double r = scene && scene->tip_radius_m() > 0 ? scene->tip_radius_m() : 0.05;
    if (scene) {
      for (const auto& o : scene->objects()) {
        if (o.kind() == OBJECT_DEFORMABLE_MESH && o.size_m()[0] > 0.0) {
          return Eigen::Vector3d(o.position_m()[0], o.position_m()[1],
                                 o.position_m()[2] + o.size_m()[0] + r);
        }
      }
      for (const auto& o : scene->objects()) {
        if (o.kind() == OBJECT_PLANE && o.normal()[2] > 0.99) {
          return Eigen::Vector3d(tip.x(), tip.y(), o.offset_m() + r);
        }
      }
    }
    return tip;
  }

  std::unique_ptr<HapticDevice> make_device() {
    if (auto hw = make_hardware_device(options.device)) return hw;  // evdev:..., vendor
    if (options.device == "replay") {
      return std::make_unique<ReplayDevice>(options.replay_file);
    }
    if (options.device == "external") {
      return std::make_unique<ExternalDevice>(DeviceSpec{}, 0.01);
    }
    SimulatedDeviceParams dp;
    if (options.script == "press-slip") {
      dp.script = press_slip_script(Eigen::Vector3d::Zero(), options.press_depth_m);
    } else {
      dp.script.kind = parse_script_kind(options.script);
      // free-motion scripts start 5 cm above the contact point
      dp.script.start_m = Eigen::Vector3d(0.0, 0.0, 0.05);
      dp.script.line_end_m = dp.script.start_m + Eigen::Vector3d(0.05, 0.0, 0.0);
    }
    dp.script.tremor_amplitude_m = options.tremor_m;
    return std::make_unique<SimulatedDevice>(dp);
  }

  int run() {
    install_stop_signal_handlers();
    // 1. wait for the server: a matched command reader, a first SlaveState and the scene
    const std::int64_t wait_start = now_ns();
    std::int64_t first_state_ns = 0;
    while (!stop_requested()) {
      const bool ready = command_writer.matched() > 0 && mailbox.version() > 0;
      if (ready && first_state_ns == 0) first_state_ns = now_ns();
      if (ready && (scene_box.version() > 0 || seconds_between(first_state_ns, now_ns()) > 2.0)) {
        break;
      }
      if (seconds_between(wait_start, now_ns()) > options.wait_server_s) {
        std::cerr << "teleop_master: no server answered on domain " << options.dds.domain
                  << " (profile " << options.dds.profile << ") within " << options.wait_server_s
                  << " s\n";
        return 3;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    if (stop_requested()) return 0;
    const double wait_s = seconds_between(wait_start, now_ns());
    Received rx;
    std::uint64_t seen = 0;
    mailbox.take_if_newer(rx, seen);
    const std::uint64_t server_received_at_start = rx.state.commands_received();
    SceneDescription scene;
    std::uint64_t scene_seen = 0;
    const bool have_scene = scene_box.take_if_newer(scene, scene_seen);
    const Eigen::Vector3d tip0 = detail::get3(rx.state.tip_position_m());

    // 2. device, controller, channels, safety, metrics (all allocation happens here)
    ControllerParams cp = options.controller;
    cp.workspace.offset_m = contact_point(have_scene ? &scene : nullptr, tip0);
    std::unique_ptr<HapticDevice> device = make_device();
    device->configure();
    device->activate();
    std::unique_ptr<BilateralController> controller = make_controller(cp.scheme);
    controller->configure(cp, device->spec());
    // a session id the server has not seen from an earlier master (it restarts its wave /
    // TDPA state when the id changes)
    controller->set_session_id(static_cast<std::uint32_t>(now_ns() / 1000) | 1u);
    DelayChannel<SlaveCommand> to_slave(options.forward);
    DelayChannel<SlaveSample> to_master(options.backward);
    SafetyLayer safety;
    SafetyParams sp = options.safety;
    safety.configure(sp, device->spec());
    SessionMetrics metrics;
    ExternalDevice* external = dynamic_cast<ExternalDevice*>(device.get());

    std::unique_ptr<CsvWriter> log;
    if (!options.log_csv.empty()) {
      log = std::make_unique<CsvWriter>(options.log_csv,
                                        std::vector<std::string>{"t_s",
                                                                 "phase",
                                                                 "seq",
                                                                 "xm_x",
                                                                 "xm_y",
                                                                 "xm_z",
                                                                 "xs_x",
                                                                 "xs_y",
                                                                 "xs_z",
                                                                 "fe_x",
                                                                 "fe_y",
                                                                 "fe_z",
                                                                 "fm_x",
                                                                 "fm_y",
                                                                 "fm_z",
                                                                 "rtt_ms",
                                                                 "link_ok",
                                                                 "in_contact",
                                                                 "penetration_m",
                                                                 "energy_j",
                                                                 "safety_scale",
                                                                 "position_error_m",
                                                                 "deformation_m",
                                                                 "loop_delay_ms",
                                                                 "delay_injected_ms",
                                                                 "passivity_observer_j",
                                                                 "passivity_dissipated_j"});
    }

    if (!options.quiet) {
      std::fprintf(stderr,
                   "teleop_master: server found after %.3f s (scene '%s'); %s, device %s, "
                   "script %s, contact point (%.3f, %.3f, %.3f) m, %s / %s\n",
                   wait_s, have_scene ? scene.name().c_str() : "?", cp.scheme.c_str(),
                   options.device.c_str(), options.script.c_str(), cp.workspace.offset_m.x(),
                   cp.workspace.offset_m.y(), cp.workspace.offset_m.z(),
                   options.forward.describe().c_str(), options.backward.describe().c_str());
    }

    const double dt = 1.0 / options.rate_hz;
    RateLoop loop(options.rate_hz);
    RttTracker rtt(1 << 20);
    std::vector<double> entry_time_s(kEntryRing, 0.0);
    std::uint64_t last_used_seq = 0;
    SampleWindow loop_delay_ms(1 << 20);
    double last_loop_delay_ms = std::nan("");
    MasterCommand cmd;
    MasterState ms;
    SlaveSample newest;
    double last_rx_s = -1.0;
    std::uint64_t seq = 0;
    std::uint64_t sent = 0;
    std::uint64_t link_losses = 0;
    bool was_link_lost = false;
    double last_rtt = std::nan("");
    const auto state_every = std::max<std::uint64_t>(
        1, static_cast<std::uint64_t>(std::llround(options.rate_hz / options.state_rate_hz)));

    // homing: slave from where it is to the mapped start of the script, no force rendered
    const Eigen::Vector3d home_goal = cp.workspace.to_slave_position(device->read().position_m);
    const double homing_time = options.homing_s;
    const double session_length =
        options.duration_s > 0 ? options.duration_s
                               : (options.device == "simulated"
                                      ? std::max(2.0, script_duration_s(make_device_script()) + 1.0)
                                      : 10.0);
    bool homing = homing_time > 0.0;
    const std::int64_t t0 = now_ns();
    std::int64_t t_session = homing ? 0 : t0;
    std::uint64_t cycles = 0;
    if (!homing) controller->activate(device->read());
    Eigen::Vector3d xs = tip0;
    Eigen::Vector3d homing_target = tip0;
    DeviceState device_sample;
    std::uint64_t device_seen = 0;

    while (!stop_requested()) {
      const std::int64_t now = now_ns();
      const double now_s = static_cast<double>(now) * 1e-9;
      if (options.samples > 0 && cycles >= options.samples) break;
      if (!homing && seconds_between(t_session, now) >= session_length) break;
      ++cycles;

      // newest SlaveState into the backward channel
      if (mailbox.take_if_newer(rx, seen)) {
        // network round trip: DDS write of the command -> receipt of its echo
        const double r = rtt.on_echo(rx.state.command_seq(), rx.state.command_send_time_ns(),
                                     rx.receive_ns, seq);
        if (r >= 0) last_rtt = r;
        const SlaveSample s = from_idl(rx.state);
        if (s.valid) to_master.push(s, now_s);
      }
      if (external && device_box.take_if_newer(device_sample, device_seen)) {
        external->on_sample(from_idl(device_sample));
      }
      if (to_master.pop_newest(now_s, newest)) {
        last_rx_s = now_s;
        xs = newest.position_m;
        // loop delay: the command entered the forward channel -> its echo reaches the controller
        if (newest.command_seq > last_used_seq && newest.command_seq <= seq &&
            newest.command_seq + kEntryRing > seq) {
          last_used_seq = newest.command_seq;
          const double d = now_s - entry_time_s[newest.command_seq % kEntryRing];
          loop_delay_ms.record(d * 1e3);
          last_loop_delay_ms = d * 1e3;
        }
      }

      const bool homing_now = homing;
      const DeviceReading reading = device->read();
      ControlOutput out;
      Eigen::Vector3d f = Eigen::Vector3d::Zero();
      SlaveCommand c;
      if (homing) {
        const double th = seconds_between(t0, now);
        const double s = min_jerk(th, homing_time);
        c.position_m = tip0 + s * (home_goal - tip0);
        homing_target = c.position_m;
        c.orientation = Eigen::Quaterniond::Identity();
        c.position_gain_n_per_m = cp.slave_stiffness_n_per_m;
        c.enabled = true;
        device->write(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
        // done once the path is over and the slave is there (or 3 s more have passed)
        if (th >= homing_time && ((xs - home_goal).norm() < 0.005 || th > homing_time + 3.0)) {
          homing = false;
          t_session = now;
          controller->activate(device->read());
          last_rx_s = now_s;
        }
      } else {
        out = controller->update(reading, newest, dt);
        f = safety.filter(now_s, dt, out.force_n, last_rx_s, controller->force_limit_n(), metrics);
        device->write(f, out.torque_nm);
        c = out.command;
      }
      c.seq = ++seq;
      c.send_time_s = now_s;
      entry_time_s[seq % kEntryRing] = now_s;
      to_slave.push(c, now_s);
      while (to_slave.pop(now_s, c)) {
        to_idl(c, now_ns(), cmd);  // send time = DDS write time: the echo gives the network RTT
        if (command_writer.write(cmd)) ++sent;
      }
      if (external && device_command_writer) {
        DeviceCommand dc = to_idl(external->next_command(), now);
        device_command_writer->write(dc);
      }

      MetricsSample m;
      m.time_s = seconds_between(t0, now);
      m.dt_s = dt;
      m.master_position_m = homing_now ? homing_target : out.command.position_m;
      m.slave_position_m = newest.position_m;
      m.have_slave = newest.valid;
      m.master_velocity_mps = reading.linear_velocity_mps;
      m.device_force_n = f;
      m.environment_force_n = controller->environment_force_gain() *
                              cp.workspace.to_master_force(newest.contact_force_n);
      m.in_contact = newest.in_contact;
      m.force_limit_n = controller->force_limit_n();
      m.link_ok = !safety.link_lost();
      m.safety_scale = safety.scale();
      if (!homing_now) {
        metrics.update(m);
        device->advance(dt);
      }
      if (safety.link_lost() && !was_link_lost) ++link_losses;
      was_link_lost = safety.link_lost();
      sim::SimEvent se;
      while (safety.events().pop(se)) {
        event(static_cast<std::uint8_t>(se.kind), static_cast<std::uint8_t>(se.severity),
              se.message, se.value);
      }

      if (cycles % state_every == 0) {
        detail::put3(ms.device_position_m(), reading.position_m);
        detail::put_q(ms.device_orientation_wxyz(), reading.orientation);
        detail::put3(ms.device_velocity_mps(), reading.linear_velocity_mps);
        detail::put3(ms.rendered_force_n(), f);
        detail::put3(ms.environment_force_n(), m.environment_force_n);
        ms.seq(cycles);
        ms.time_ns(now);
        ms.position_error_m((m.master_position_m - newest.position_m).norm());
        ms.passivity_energy_j(metrics.energy_j());
        ms.rtt_ms(last_rtt);
        ms.mode(static_cast<std::uint8_t>(controller->scheme()));
        ms.link_ok(!safety.link_lost());
        const BilateralController::PassivityStatus ps = controller->passivity_status();
        ms.passivity_observer_j(ps.observer_j);
        ms.passivity_dissipated_j(ps.dissipated_j);
        state_writer.write(ms);
        state_views.offer(ms);  // a copy under a try-lock; the views are written elsewhere
      }
      if (log) {
        const double t = seconds_between(t0, now);
        const BilateralController::PassivityStatus ps = controller->passivity_status();
        const Eigen::Vector3d& xm = m.master_position_m;
        const Eigen::Vector3d& fe = newest.contact_force_n;
        const auto vals =
            csv_row(t, homing_now ? 0.0 : 1.0, static_cast<double>(seq), xm.x(), xm.y(), xm.z(),
                    newest.position_m.x(), newest.position_m.y(), newest.position_m.z(), fe.x(),
                    fe.y(), fe.z(), f.x(), f.y(), f.z(), last_rtt, safety.link_lost() ? 0.0 : 1.0,
                    newest.in_contact ? 1.0 : 0.0, newest.penetration_m, metrics.energy_j(),
                    safety.scale(), (xm - newest.position_m).norm(), newest.deformation_m,
                    last_loop_delay_ms, (options.forward.delay_s + options.backward.delay_s) * 1e3,
                    ps.observer_j, ps.dissipated_j);
        log->row(vals.data(), vals.size());
      }
      loop.wait();
    }
    controller->deactivate();
    device->write(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
    device->deactivate();
    const double elapsed = seconds_between(t0, now_ns());
    const double session_s = t_session ? seconds_between(t_session, now_ns()) : 0.0;

    // drain: late echoes and the server's final receive count
    const std::int64_t drain_start = now_ns();
    while (seconds_between(drain_start, now_ns()) < options.drain_s) {
      if (mailbox.take_if_newer(rx, seen)) {
        rtt.on_echo(rx.state.command_seq(), rx.state.command_send_time_ns(), rx.receive_ns, seq);
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    state_reader->stop();

    const std::uint64_t server_received =
        rx.state.commands_received() >= server_received_at_start
            ? rx.state.commands_received() - server_received_at_start
            : 0;
    const std::uint64_t received = std::min(server_received, sent);
    const auto fwd = to_slave.report();
    const auto bwd = to_master.report();
    metrics.set_losses(fwd.counters.pushed, fwd.counters.pushed - fwd.counters.delivered,
                       bwd.counters.pushed, bwd.counters.pushed - bwd.counters.delivered);
    const Summary r = summarize(rtt.rtt_ms().snapshot());
    const Summary j = summarize(loop.lateness_us().snapshot());
    const Summary ld = summarize(loop_delay_ms.snapshot());
    if (!options.summary_json.empty()) {
      std::ofstream out(options.summary_json);
      out << "{\n"
          << "  \"duration_s\": " << json_number(elapsed) << ",\n"
          << "  \"session_s\": " << json_number(session_s) << ",\n"
          << "  \"rate_hz\": " << json_number(options.rate_hz) << ",\n"
          << "  \"scheme\": \"" << cp.scheme << "\",\n"
          << "  \"device\": \"" << options.device << "\",\n"
          << "  \"script\": \"" << options.script << "\",\n"
          << "  \"sent\": " << sent << ",\n"
          << "  \"received\": " << received << ",\n"
          << "  \"lost\": " << (sent - received) << ",\n"
          << "  \"echoed\": " << rtt.unique_echoes() << ",\n"
          << "  \"states_received\": " << states_received.load() << ",\n"
          << "  \"rtt_ms\": {\"p50\": " << json_number(r.p50) << ", \"p90\": " << json_number(r.p90)
          << ", \"p99\": " << json_number(r.p99) << ", \"p999\": " << json_number(r.p999)
          << ", \"max\": " << json_number(r.max) << ", \"mean\": " << json_number(r.mean)
          << ", \"count\": " << r.count << "},\n"
          << "  \"loop_delay_ms\": {\"p50\": " << json_number(ld.p50)
          << ", \"p99\": " << json_number(ld.p99) << ", \"max\": " << json_number(ld.max)
          << ", \"count\": " << ld.count << "},\n"
          << "  \"loop_jitter_us\": {\"p50\": " << json_number(j.p50)
          << ", \"p99\": " << json_number(j.p99) << ", \"max\": " << json_number(j.max) << "},\n"
          << "  \"overruns\": " << loop.overruns() << ",\n"
          << "  \"link_losses\": " << link_losses << ",\n"
          << "  \"wait_server_s\": " << json_number(wait_s) << ",\n"
          << "  \"verdict\": \"" << verdict_name(metrics.verdict()) << "\",\n"
          << "  \"metrics\": " << metrics.summary_json() << ",\n"
          << "  \"delay\": {\"forward\": " << channel_json(fwd)
          << ", \"backward\": " << channel_json(bwd) << "},\n"
          << "  \"safety\": {\"cut\": " << (safety.cut() ? "true" : "false") << ", \"reason\": \""
          << safety.cut_reason() << "\", \"max_output_n\": " << json_number(safety.max_output_n())
          << "}\n"
          << "}\n";
    }
    if (!options.quiet) {
      std::fprintf(
          stdout,
          "session summary (%s, %s, script %s)\n"
          "  duration        %.2f s (%.2f s of session after homing) at %.0f Hz\n"
          "  commands        %llu sent, %llu received by the server, %llu lost (%.2f%%)\n"
          "  injected delay  forward %s; measured mean %.2f ms, p99 %.2f ms, lost %.2f%%\n"
          "                  backward %s; measured mean %.2f ms, p99 %.2f ms, lost %.2f%%\n"
          "  round trip      p50 %.3f ms  p99 %.3f ms  max %.3f ms  (%zu echoes, network)\n"
          "  loop delay      p50 %.3f ms  p99 %.3f ms  (command in -> its echo used)\n"
          "  loop jitter     p50 %.1f us  p99 %.1f us  (%llu overruns)\n"
          "  tracking        position error RMS %.2f mm, max %.2f mm\n"
          "  force           max rendered %.2f N, force error RMS %.3f N, contact %.2f s, "
          "mean contact force %.2f N\n"
          "  passivity       energy at the master port %.4f J (min %.4f J)\n"
          "  safety          %s%s, link losses %llu\n"
          "  verdict         %s%s%s\n",
          cp.scheme.c_str(), options.device.c_str(), options.script.c_str(), elapsed, session_s,
          options.rate_hz, static_cast<unsigned long long>(sent),
          static_cast<unsigned long long>(received),
          static_cast<unsigned long long>(sent - received),
          sent ? 100.0 * static_cast<double>(sent - received) / static_cast<double>(sent) : 0.0,
          options.forward.describe().c_str(), fwd.delay_mean_ms, fwd.delay_p99_ms,
          100.0 * fwd.loss_fraction, options.backward.describe().c_str(), bwd.delay_mean_ms,
          bwd.delay_p99_ms, 100.0 * bwd.loss_fraction, r.p50, r.p99, r.max, r.count, ld.p50, ld.p99,
          j.p50, j.p99, static_cast<unsigned long long>(loop.overruns()),
          metrics.position_error_rms_m() * 1e3, metrics.position_error_max_m() * 1e3,
          metrics.max_device_force_n(), metrics.force_error_rms_n(), metrics.contact_time_s(),
          metrics.mean_contact_force_n(), metrics.energy_j(), metrics.energy_min_j(),
          safety.cut() ? "CUT: " : "ok", safety.cut() ? safety.cut_reason() : "",
          static_cast<unsigned long long>(link_losses), verdict_name(metrics.verdict()),
          *metrics.verdict_reason() ? " - " : "", metrics.verdict_reason());
    }
    return 0;
  }

  OperatorScript make_device_script() const {
    if (options.script == "press-slip") {
      return press_slip_script(Eigen::Vector3d::Zero(), options.press_depth_m);
    }
    OperatorScript s;
    s.kind = parse_script_kind(options.script);
    return s;
  }
};

MasterNode::MasterNode(const MasterOptions& options) : impl_(std::make_unique<Impl>(options)) {}
MasterNode::~MasterNode() = default;
int MasterNode::run() { return impl_->run(); }

}  // namespace teleop::master
