#include "client/node/master_node.hpp"

#include <Eigen/Core>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <iostream>
#include <limits>
#include <thread>

#include "client/cycle/master_cycle.hpp"
#include "client/device/device_factory.hpp"
#include "client/device/device_idl.hpp"
#include "client/device/external_device.hpp"
#include "client/device/replay_device.hpp"
#include "client/device/simulated_device.hpp"
#include "client/metrics/link_verdict.hpp"
#include "client/metrics/session_metrics.hpp"
#include "client/net/delay_channel.hpp"
#include "client/node/dds_slave_link.hpp"
#include "client/node/device_driver_latch.hpp"
#include "client/node/experiment_publisher.hpp"
#include "client/node/master_report.hpp"
#include "client/node/master_session.hpp"
#include "client/node/server_binding.hpp"
#include "client/node/server_health.hpp"
#include "client/node/server_word.hpp"
#include "client/node/tuning_endpoint.hpp"
#include "common/dds/async_writer.hpp"
#include "common/dds/contact_point.hpp"
#include "common/dds/endpoint.hpp"
#include "common/dds/event_publisher.hpp"
#include "common/dds/rate_limited_publisher.hpp"
#include "common/dds/teleop_idl.hpp"
#include "common/util/clock.hpp"
#include "common/util/exit_codes.hpp"
#include "common/util/files.hpp"
#include "common/util/progress.hpp"
#include "common/util/rate_loop.hpp"
#include "common/util/signals.hpp"
#include "teleop/idl/DevicePubSubTypes.h"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::master {

namespace {

/// The session's time line on stderr (progress_stream(): a terminal, or --progress), drawn by a
/// thread of its own four times a second: the haptic loop neither prints nor waits for it.
class SessionStatus {
 public:
  explicit SessionStatus(double length_s)
      : progress_(progress_stream(), "teleop_master session", length_s, "s", 1) {
    if (!progress_.active()) return;
    thread_ = std::thread([this] {
      while (!done_.load()) {
        progress_.set(progress_.elapsed_s());
        std::this_thread::sleep_for(std::chrono::milliseconds(250));
      }
    });
  }
  SessionStatus(const SessionStatus&) = delete;
  SessionStatus& operator=(const SessionStatus&) = delete;
  ~SessionStatus() { stop(); }
  /// The final line (once).
  void stop() {
    done_.store(true);
    if (thread_.joinable()) thread_.join();
    progress_.set(progress_.elapsed_s());
    progress_.finish();
  }

 private:
  Progress progress_;
  std::atomic<bool> done_{false};
  std::thread thread_;
};

/// Internal status of Impl::run: make a new participant and wait again.
constexpr int kReconnect = -2;

}  // namespace

/// The haptic loop's state across its cycles (MasterNode::Impl::run_loop): the session's
/// bookkeeping (MasterSession) and the buffers a cycle fills, made before the first cycle so that
/// a cycle allocates nothing.
struct LoopState {
  LoopState(MasterCycle& c, RateLoop& l, DdsSlaveLink& k, ExternalDevice* e, SessionReport& r,
            const SessionPlan& plan, std::int64_t t0_ns)
      : cycle(c), loop(l), link(k), external(e), rep(r), session(plan, t0_ns) {}
  MasterCycle& cycle;
  RateLoop& loop;
  DdsSlaveLink& link;
  ExternalDevice* external;  // the device, when it is driven over teleop/device_state
  SessionReport& rep;
  MasterSession session;
  MasterState ms;             // MasterState for observers, filled in place
  DeviceState device_sample;  // the newest teleop/device_state sample (external device)
  std::uint64_t device_seen = 0;
  std::function<void(std::uint8_t, const std::string&)> report_tuning;  // TuningEndpoint::poll
};

struct MasterNode::Impl {
  MasterOptions options;
  // this master's session id; the one server it believes (SlaveState, ServerStats, server
  // events): declared before the readers whose threads use it
  std::uint32_t master_session = static_cast<std::uint32_t>(now_ns() >> 10) | 1u;
  ServerBinding binding{master_session,
                        static_cast<std::int64_t>(options.safety.link_timeout_s * 1e9)};
  dds::Participant participant;
  // every write of the haptic loop goes through a network thread: it never waits on the
  // network (a TCP link that is cut or congested blocks the DataWriter, not the loop)
  DdsSlaveLink::CommandWriter command_writer;
  dds::LatestWriter<MasterStatePubSubType> state_writer;
  dds::EventPublisher event_publisher;
  // observers' rate-limited copies of MasterState, written from their own thread: the haptic
  // loop's cost does not grow with the number of observers (docs/topics.md)
  dds::RateLimitedPublisher<MasterStatePubSubType> state_views;
  dds::Mailbox<ReceivedState> mailbox;
  dds::Mailbox<SceneDescription> scene_box;
  SceneDescription scene_at_start;  ///< the scene as the session began (empty if none came)
  std::atomic<std::uint64_t> states_received{0};
  std::unique_ptr<dds::Reader<SlaveStatePubSubType>> state_reader;
  std::unique_ptr<dds::Reader<SceneDescriptionPubSubType>> scene_reader;
  // external device transport (only with --device external)
  std::unique_ptr<dds::LatestWriter<DeviceCommandPubSubType>> device_command_writer;
  std::unique_ptr<dds::Reader<DeviceStatePubSubType>> device_state_reader;
  dds::Mailbox<DeviceState> device_box;
  DeviceDriverLatch device_driver;  // one driver at a time on teleop/device_state
  bool device_foreign_reported = false;
  std::unique_ptr<CycleLog> log;
  // the server's health: ServerStats counters and fault events received during the session
  std::unique_ptr<dds::Reader<ServerStatsPubSubType>> stats_reader;
  std::unique_ptr<dds::Reader<EventPubSubType>> events_reader;
  dds::Mailbox<ServerStats> stats_box;
  ServerWord server_word{master_session};  // faults, ownership and clamps the server reported
  ServerHealth health;
  std::uint64_t stats_seen = 0;
  bool second_server_reported = false;

  std::unique_ptr<TuningEndpoint> tuning;  // live tuning (teleop/tuning, teleop/tuning_status)
  std::unique_ptr<ExperimentPublisher> experiment;  // teleop/experiment, latched
  double waited_s = 0.0;  // time run() waited for the server before returning kReconnect
  bool tcp_client = false;

  explicit Impl(const MasterOptions& o)
      : options(o),
        participant(o.dds),
        command_writer(participant, dds::topics::kMasterCommand),
        state_writer(participant, dds::topics::kMasterState),
        event_publisher(participant, "master"),
        state_views(participant,
                    {{dds::topics::kMasterStateView, dds::topics::kViewRateHz},
                     {dds::topics::kMasterStateMonitor, dds::topics::kMonitorRateHz}}) {
    dds::ProfileKind kind = dds::ProfileKind::kUdp;
    (void)dds::participant_qos(o.dds, &kind);
    tcp_client = kind == dds::ProfileKind::kTcp;

    state_reader = std::make_unique<dds::Reader<SlaveStatePubSubType>>(
        participant, dds::topics::kSlaveState,
        [this](const SlaveState& s, const eprosima::fastdds::dds::SampleInfo& info) {
          if (!binding.accept_state(info.sample_identity.writer_guid().guidPrefix,
                                    s.owner_session(), s.owner_active(), now_ns())) {
            return;  // another participant's: counted by the binding
          }
          states_received.fetch_add(1);
          mailbox.put(ReceivedState{s, now_ns()});
        });
    scene_reader = std::make_unique<dds::Reader<SceneDescriptionPubSubType>>(
        participant, dds::topics::kScene,
        [this](const SceneDescription& s, const eprosima::fastdds::dds::SampleInfo&) {
          scene_box.put(s);
        });
    stats_reader = std::make_unique<dds::Reader<ServerStatsPubSubType>>(
        participant, dds::topics::kServerStats,
        [this](const ServerStats& s, const eprosima::fastdds::dds::SampleInfo& info) {
          if (binding.accept(ServerBinding::kStats,
                             info.sample_identity.writer_guid().guidPrefix)) {
            stats_box.put(s);
          }
        });
    events_reader = std::make_unique<dds::Reader<EventPubSubType>>(
        participant, dds::topics::kEvents,
        [this](const Event& e, const eprosima::fastdds::dds::SampleInfo& info) {
          // the server's events only from the server this master is bound to
          if (e.source() == "server" &&
              !binding.accept(ServerBinding::kEvent,
                              info.sample_identity.writer_guid().guidPrefix)) {
            return;
          }
          server_word.on_event(e, now_ns());
        });
    tuning = std::make_unique<TuningEndpoint>(participant, master_session, o.accept_tuning);
    experiment = std::make_unique<ExperimentPublisher>(participant);
    if (o.device == "external") {
      device_command_writer = std::make_unique<dds::LatestWriter<DeviceCommandPubSubType>>(
          participant, dds::topics::kDeviceCommand);
      device_state_reader = std::make_unique<dds::Reader<DeviceStatePubSubType>>(
          participant, dds::topics::kDeviceState,
          [this](const DeviceState& s, const eprosima::fastdds::dds::SampleInfo& info) {
            if (device_driver.accept(info.publication_handle, now_ns())) device_box.put(s);
          });
    }
  }

  /// Publishes one of this master's events (about its own session) and prints a warning or an
  /// error unless quiet.
  void event(std::uint8_t kind, std::uint8_t severity, const std::string& msg, double value) {
    sim::EventTags tags;
    tags.session = master_session;
    event_publisher.publish(static_cast<sim::EventKind>(kind), static_cast<sim::Severity>(severity),
                            msg.c_str(), value, tags);
    if (!options.quiet && severity > 0) std::cerr << "teleop_master: " << msg << "\n";
  }

  /// Where the master's origin lands in the slave world: the flag's point, else where the tip
  /// touches the scene's target (common/dds/contact_point.hpp).
  Eigen::Vector3d contact_point(const SceneDescription* scene, const Eigen::Vector3d& tip) {
    if (options.has_contact_point) return options.contact_point_m;
    return dds::scene_contact_point(scene, tip);
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

  /// Waits for a matched command reader, a first SlaveState and the scene (or 2 s more).
  /// Returns -1 when the server is there, kReconnect when a TCP client should make a new
  /// participant (see MasterNode::run), else the exit status (3: no server, 0: stopped).
  /// `waited_before_s`: time already spent waiting by earlier participants.
  int wait_for_server(double& wait_s, double waited_before_s = 0.0) {
    const std::int64_t wait_start = now_ns();
    std::int64_t first_state_ns = 0;
    while (!stop_requested()) {
      // Fast DDS 2.9's TCP client has been seen (multi-host test, about one connection in
      // sixteen) never to complete its connection to a running server: a new participant
      // makes a new connection
      if (tcp_client && mailbox.version() == 0 && options.reconnect_s > 0.0 &&
          seconds_between(wait_start, now_ns()) > options.reconnect_s &&
          waited_before_s + seconds_between(wait_start, now_ns()) < options.wait_server_s) {
        wait_s = waited_before_s + seconds_between(wait_start, now_ns());
        return kReconnect;
      }
      const bool ready = command_writer.matched() > 0 && mailbox.version() > 0;
      if (ready && first_state_ns == 0) first_state_ns = now_ns();
      if (ready && (scene_box.version() > 0 || seconds_between(first_state_ns, now_ns()) > 2.0)) {
        wait_s = seconds_between(wait_start, now_ns());
        return -1;
      }
      if (waited_before_s + seconds_between(wait_start, now_ns()) > options.wait_server_s) {
        std::cerr << "teleop_master: no server answered on domain " << options.dds.domain
                  << " (profile " << options.dds.profile << ") within " << options.wait_server_s
                  << " s\n";
        return 3;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return 0;
  }

  void open_log() {
    if (options.log_csv.empty()) return;
    log = std::make_unique<CycleLog>(options.log_csv,
                                     (options.forward.delay_s + options.backward.delay_s) * 1e3);
  }

  /// MasterState for observers (every state_every cycles).
  void publish_state(const MasterCycle& cycle, std::uint64_t cycles, std::int64_t now,
                     double rtt_ms, MasterState& ms) {
    const MetricsSample& m = cycle.last_sample();
    const DeviceReading& reading = cycle.reading();
    detail::put3(ms.device_position_m(), reading.position_m);
    detail::put_q(ms.device_orientation_wxyz(), reading.orientation);
    detail::put3(ms.device_velocity_mps(), reading.linear_velocity_mps);
    detail::put3(ms.rendered_force_n(), cycle.device_force_n());
    detail::put3(ms.environment_force_n(), m.environment_force_n);
    ms.seq(cycles);
    ms.time_ns(now);
    ms.position_error_m((m.master_position_m - cycle.slave_at_master().position_m).norm());
    ms.passivity_energy_j(cycle.metrics().energy_j());
    ms.rtt_ms(rtt_ms);
    ms.mode(static_cast<std::uint8_t>(cycle.controller().scheme()));
    ms.link_ok(!cycle.safety().link_lost());
    const BilateralController::PassivityStatus ps = cycle.controller().passivity_status();
    ms.passivity_observer_j(ps.observer_j);
    ms.passivity_dissipated_j(ps.dissipated_j);
    detail::put3(ms.command_position_m(), m.master_position_m);
    state_writer.write(ms);
    state_views.offer(ms);  // a copy under a try-lock; the views are written elsewhere
  }

  /// The session's figures once the loop and the drain are over.
  void fill_report(MasterCycle& cycle, DdsSlaveLink& link, const RateLoop& loop,
                   SessionReport& rep) {
    // commands sent while another master owned the slave are not this session's (commands lost
    // on the way before the first one arrived are: only a refusal seen moves the start)
    if (rep.refused_first) {
      rep.issued_before_owning =
          link.first_owned_seq() > 0 ? link.first_owned_seq() - 1 : cycle.command_seq();
    }
    rep.issued = cycle.command_seq() - rep.issued_before_owning;
    rep.in_flight = std::min<std::uint64_t>(cycle.forward().in_flight(), rep.issued);
    {
      const ChannelCounters& fw = cycle.forward().counters();
      rep.dropped = fw.lost_random + fw.lost_burst + fw.lost_overflow + fw.lost_window;
    }
    // handed to the network thread and not replaced by a newer command before it was written
    rep.sent = link.sent() - std::min(link.sent(), command_writer.dropped());
    rep.received = std::min(link.received_in_session(), rep.sent);
    rep.server_faults = update_health();
    if (rep.server_faults > 0) {
      cycle.metrics().mark_unstable("the slave faulted on the server", rep.elapsed_s);
    }
    rep.server_watchdog_trips = health.watchdog_trips.total();
    rep.server_overruns = health.overruns.total();
    rep.server_rejected = health.rejected.total();
    rep.server_restarts = std::max(health.restarts, link.restarts());
    rep.echoed = link.rtt().unique_echoes();
    rep.states_received = states_received.load();
    rep.overruns = loop.overruns();
    rep.forward = cycle.forward().report();
    rep.backward = cycle.backward().report();
    rep.rtt_ms = summarize(link.rtt().rtt_ms().snapshot());
    count_network_threads(rep);
    rep.jitter_us = summarize(loop.lateness_us().snapshot());
    rep.owner_message = server_word.ownership();
    rep.server_gain_clamp = server_word.gain_clamp();
  }

  /// The scene as the session begins into scene_at_start; false when none came.
  bool take_scene() {
    SceneDescription scene;
    std::uint64_t scene_seen = 0;
    if (!scene_box.take_if_newer(scene, scene_seen)) return false;
    scene_at_start = std::move(scene);
    return true;
  }

  /// The cycle's configuration from the options; the master's origin maps to `contact_point_m`.
  MasterCycleConfig cycle_config(const Eigen::Vector3d& contact_point_m) const {
    MasterCycleConfig cc;
    cc.controller = options.controller;
    cc.controller.workspace.offset_m = contact_point_m;
    cc.forward = options.forward;
    cc.backward = options.backward;
    cc.safety = options.safety;
    cc.dt_s = 1.0 / options.rate_hz;
    if (options.command_rate_hz > 0.0) {
      cc.command_every = static_cast<std::uint32_t>(
          std::max(1.0, std::round(options.rate_hz / options.command_rate_hz)));
    }
    cc.delivery = ForwardDelivery::kEveryDue;
    cc.driver_timeout_s = options.driver_timeout_s;
    // a session id the server has not seen from an earlier master (it restarts its passivity
    // port state when the id changes)
    cc.session_id = static_cast<std::uint32_t>(now_ns() / 1000) | 1u;
    return cc;
  }

  /// The line on stderr once the server answered.
  void announce_start(const MasterCycleConfig& cc, double wait_s, bool have_scene) const {
    if (options.quiet) return;
    std::fprintf(stderr,
                 "teleop_master: server found after %.3f s (scene '%s'); %s, device %s, "
                 "script %s, contact point (%.3f, %.3f, %.3f) m, %s / %s\n",
                 wait_s, have_scene ? scene_at_start.name().c_str() : "?",
                 cc.controller.scheme.c_str(), options.device.c_str(), options.script.c_str(),
                 cc.controller.workspace.offset_m.x(), cc.controller.workspace.offset_m.y(),
                 cc.controller.workspace.offset_m.z(), options.forward.describe().c_str(),
                 options.backward.describe().c_str());
  }

  /// After the loop: keep reading for drain_s (late echoes and the server's final receive
  /// count), then stop the state reader.
  void drain(DdsSlaveLink& link) {
    const std::int64_t drain_start = now_ns();
    while (seconds_between(drain_start, now_ns()) < options.drain_s) {
      link.drain();
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    state_reader->stop();
  }

  /// The session's report out (the log closed, the JSON summary, the printout). Returns the exit
  /// status: refused, or the verdict's.
  int finish_session(const MasterCycle& cycle, const SessionReport& rep) {
    // a file that could not be written is an error naming it, after everything else is out
    std::string write_error;
    try {
      if (log) log->close();
    } catch (const std::exception& e) {
      write_error = e.what();
    }
    if (!options.summary_json.empty()) {
      write_session_summary_json(options.summary_json, cycle, rep, report_context());
    }
    if (!options.quiet) {
      std::fputs(session_summary_text(cycle, rep, report_context()).c_str(), stdout);
    }
    if (!write_error.empty()) throw std::runtime_error(write_error);
    if (rep.refused) {
      std::cerr << "teleop_master: refused: another master owns the slave ("
                << (rep.owner_message.empty() ? "the server's state names its session"
                                              : rep.owner_message)
                << "); no force was rendered"
                << (options.wait_owner_s > 0
                        ? "; waited " + std::to_string(rep.waited_for_owner_s) + " s for it"
                        : "; --wait-owner SECONDS waits for it")
                << "\n";
      return exit_code::kRefused;
    }
    return session_verdict(cycle.metrics(), rep, cycle.config().controller.scheme).exit_status;
  }

  int run(double waited_before_s = 0.0) {
    install_stop_signal_handlers();
    // 1. wait for the server: a matched command reader, a first SlaveState and the scene
    double wait_s = 0.0;
    if (const int status = wait_for_server(wait_s, waited_before_s); status != -1) {
      waited_s = wait_s;
      return status;
    }
    DdsSlaveLink link(command_writer, mailbox, master_session, options.name);
    link.take_newest();
    const bool have_scene = take_scene();
    const Eigen::Vector3d tip0 = detail::get3(link.newest_state().tip_position_m());
    // 2. device, controller, channels, safety, metrics (all allocation happens here)
    const MasterCycleConfig cc =
        cycle_config(contact_point(have_scene ? &scene_at_start : nullptr, tip0));
    std::unique_ptr<HapticDevice> device = make_device();
    device->configure();
    MasterCycle cycle(cc, *device, link);
    open_log();
    announce_start(cc, wait_s, have_scene);
    // 3. the haptic loop: homing (slave from where it is to the mapped script start, no force
    // rendered), then the session, then the close
    SessionReport rep;
    rep.wait_s = wait_s;
    const DmaLatencyHold dma(options.realtime.dma_latency_us);
    if (!dma.problem().empty()) {
      std::fprintf(stderr, "teleop_master: warning: the cores may sleep deeply: %s\n",
                   dma.problem().c_str());
    }
    RateLoop loop(options.rate_hz, 65536,
                  static_cast<std::int64_t>(options.realtime.spin_us) * 1000);
    run_loop(cycle, loop, link, dynamic_cast<ExternalDevice*>(device.get()), tip0, rep);
    cycle.stop();
    // 4. drain, then the report
    drain(link);
    fill_report(cycle, link, loop, rep);
    return finish_session(cycle, rep);
  }

  /// Ownership, once per cycle: the watch decides (OwnershipWatch), the cycle holds while
  /// refused and re-homes when it gets the slave after waiting, and each change is an event.
  void watch_ownership(LoopState& s, double now_s) {
    switch (s.session.owner().update(s.link.owner(), now_s)) {
      case OwnershipWatch::Change::kGotSlave: {
        const double owner_wait_s = s.session.owner().last_wait_s();
        s.cycle.hold(false);
        s.cycle.rehome(now_s, RehomeReason::kTakeover);
        event(static_cast<std::uint8_t>(sim::EventKind::kOwnership), 1,
              "got the slave after waiting " + std::to_string(owner_wait_s) + " s", owner_wait_s);
        break;
      }
      case OwnershipWatch::Change::kRefused: {
        s.cycle.hold(true);
        char msg[160];
        std::snprintf(msg, sizeof(msg), "refused: the slave is owned by master session 0x%08x%s",
                      s.link.other_owner_session(),
                      options.wait_owner_s > 0 ? "; waiting for it" : "; no force rendered");
        event(static_cast<std::uint8_t>(sim::EventKind::kOwnership), 2, msg, 0.0);
        break;
      }
      case OwnershipWatch::Change::kNone:
        break;
    }
  }

  /// What the loop's network threads replaced, dropped or saw refused (after the session).
  void count_network_threads(SessionReport& rep) {
    rep.commands_dropped = command_writer.dropped();
    rep.command_write_failures = command_writer.failures();
    rep.states_replaced = state_writer.replaced();
    event_publisher.flush(0.5);
    rep.events_dropped = event_publisher.dropped();
    experiment->flush(0.5);
    rep.experiment_writes = experiment->written();
    rep.write_failures = state_writer.failures() + event_publisher.failures() +
                         (device_command_writer ? device_command_writer->failures() : 0) +
                         tuning->write_failures() + experiment->failures();
  }

  /// Once per session: a warning when another participant wrote the server's topics (a second
  /// server, or a rogue); its samples are ignored and counted for the summary.
  void report_second_server() {
    if (second_server_reported || binding.foreign_total() == 0) return;
    second_server_reported = true;
    event(static_cast<std::uint8_t>(sim::EventKind::kOwnership), 1,
          "ignoring teleop/slave_state, server_stats and server events from a second "
          "participant (" +
              binding.first_foreign() + "): this master is bound to server " + binding.server() +
              "; all such samples are counted in the summary",
          static_cast<double>(binding.foreign_total()));
  }

  /// A stall of the loop (StallWatch): published as an event, and the force fades out at the
  /// device's rate bound and back in over the link fade (SafetyLayer::fade_in) instead of
  /// carrying on from where it froze. `gap_s`: the stall's length [s].
  void on_stall(MasterCycle& cycle, double gap_s) {
    cycle.safety().fade_in();
    char msg[96];
    std::snprintf(msg, sizeof msg, "haptic loop stalled for %.3f s: force faded out and back in",
                  gap_s);
    event(static_cast<std::uint8_t>(sim::EventKind::kWatchdog), 1, msg, gap_s);  // and stderr
  }

  /// The end of a session: the force fades to zero at the device's rate bound while the slave
  /// holds, then this master releases the slave (three release commands, best effort).
  /// Returns the cycles it took.
  std::uint64_t close_session(MasterCycle& cycle, RateLoop& loop, DdsSlaveLink& link, double t0_s) {
    cycle.hold(true);
    const std::int64_t start = now_ns();
    std::uint64_t cycles = 0;
    while (seconds_between(start, now_ns()) < 1.0) {
      const double now_s = static_cast<double>(now_ns()) * 1e-9;
      ++cycles;
      cycle.step(now_s);
      cycle.finish(now_s);
      if (log) log->row(cycle, now_s - t0_s, link.last_rtt_ms(), std::nan(""));
      if (cycle.device_force_n().squaredNorm() == 0.0) break;
      loop.wait();
    }
    SlaveCommand release;
    release.position_m = cycle.slave_at_master().position_m;
    release.enabled = false;
    release.release = true;
    for (int k = 1; k <= 3; ++k) {
      release.seq = cycle.command_seq() + static_cast<std::uint64_t>(k);
      link.send(release);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    command_writer.flush(0.5);  // the releases leave (the network thread writes them) first
    return cycles;
  }

  /// Takes the newest ServerStats into the health counters. Returns the faults so far.
  std::uint64_t update_health() {
    ServerStats st;
    if (stats_box.take_if_newer(st, stats_seen)) {
      health.feed(st.steps(), st.faults(), st.watchdog_trips(), st.overruns(),
                  st.commands_rejected_nan() + st.commands_rejected_workspace() +
                      st.commands_rejected_stale() + st.commands_rejected_passivity());
    }
    return std::max<std::uint64_t>(health.faults.total(), server_word.faults());
  }

  /// Before the first cycle: the thread's scheduling, the server's fault baseline, homing, and
  /// the first tuning status and experiment description.
  void begin_loop(LoopState& s, const Eigen::Vector3d& tip0) {
    // made once: the loop passes it by reference every cycle without building a std::function
    s.report_tuning = [this](std::uint8_t severity, const std::string& msg) {
      event(static_cast<std::uint8_t>(sim::EventKind::kTuning), severity, msg, 0.0);
      if (!options.quiet && severity == 0) std::cerr << "teleop_master: " << msg << "\n";
    };
    if (wants_thread_setup(options.realtime)) {
      const std::string problem = make_thread_realtime(options.realtime);
      if (!problem.empty()) {
        std::cerr << "teleop_master: warning: the haptic loop stays a normal thread: " << problem
                  << "\n";
      }
    }
    update_health();  // the baseline: the server's counts from before this session
    server_word.start_session(s.session.t0_ns());
    s.cycle.start_homing(s.session.t0_s(), tip0, options.homing_s);
    tuning->publish_status(s.cycle, s.session.t0_ns());
    experiment->begin(s.cycle, master_session, options.name, options.device, options.rate_hz);
  }

  /// With --device external: the newest teleop/device_state sample into the device, and a
  /// warning once when a second driver writes that topic.
  void take_device_sample(LoopState& s) {
    if (!s.external) return;
    if (device_box.take_if_newer(s.device_sample, s.device_seen)) {
      s.external->on_sample(from_idl(s.device_sample));
    }
    if (!device_foreign_reported && device_driver.ignored() > 0) {
      device_foreign_reported = true;
      event(static_cast<std::uint8_t>(sim::EventKind::kOwnership), 1,
            "ignoring teleop/device_state from a second driver while the first one is live", 0.0);
    }
  }

  /// One haptic cycle: the device's sample, tuning, a stall, the cycle's step, the loop delay,
  /// the external device's command, ownership, then what follows from it (after_cycle).
  void run_cycle(LoopState& s, std::int64_t now) {
    const double now_s = static_cast<double>(now) * 1e-9;
    MasterCycle& cycle = s.cycle;
    LoopDelayMeter& loop_delay = s.session.loop_delay();
    take_device_sample(s);
    tuning->poll(cycle, now_s, now, s.report_tuning);
    if (const double gap_s = s.session.begin_cycle(now_s); gap_s > 0.0) on_stall(cycle, gap_s);
    cycle.step(now_s);
    loop_delay.entered(cycle.command_seq(), now_s);
    if (cycle.sample_arrived() &&
        loop_delay.echo_used(cycle.slave_at_master().command_seq, cycle.command_seq(), now_s)) {
      experiment->record_loop_delay(loop_delay.last_ms());
    }
    if (s.external && device_command_writer) {
      DeviceCommand dc = to_idl(s.external->next_command(), now);
      device_command_writer->write(dc);
    }
    watch_ownership(s, now_s);
    report_second_server();
    cycle.finish(now_s);
    experiment->update(cycle, now_s, now);
    after_cycle(s, now);
  }

  /// What follows a cycle: a fault on the server, a link loss, the safety layer's events,
  /// MasterState for observers and the log row.
  void after_cycle(LoopState& s, std::int64_t now) {
    const double now_s = static_cast<double>(now) * 1e-9;
    MasterCycle& cycle = s.cycle;
    // a session whose slave faulted is never stable
    if (s.session.faults_rose(update_health())) {
      cycle.metrics().mark_unstable("the slave faulted on the server", now_s - s.session.t0_s());
    }
    s.session.link_state(cycle.safety().link_lost());
    sim::SimEvent se;
    while (cycle.safety().events().pop(se)) {
      event(static_cast<std::uint8_t>(se.kind), static_cast<std::uint8_t>(se.severity), se.message,
            se.value);
    }
    if (s.session.state_due()) {
      publish_state(cycle, s.session.cycles(), now, s.link.last_rtt_ms(), s.ms);
    }
    if (log) {
      log->row(cycle, now_s - s.session.t0_s(), s.link.last_rtt_ms(),
               s.session.loop_delay().last_ms());
    }
  }

  /// After the last cycle: the session's and the cycle's figures into the report, then the close
  /// (close_session).
  void end_loop(LoopState& s) {
    MasterCycle& cycle = s.cycle;
    SessionReport& rep = s.rep;
    const double end_s = static_cast<double>(now_ns()) * 1e-9;
    s.session.report(end_s, cycle.session_start_s(), rep);
    rep.driver_silences = cycle.driver_silences();
    rep.driver_silent_s = cycle.driver_silent_s(end_s);
    rep.closing_cycles = close_session(cycle, s.loop, s.link, s.session.t0_s());
    rep.releases_sent = s.link.releases_sent();
  }

  /// The haptic loop until the session length, the sample limit, a refusal or a stop signal,
  /// then the close.
  void run_loop(MasterCycle& cycle, RateLoop& loop, DdsSlaveLink& link, ExternalDevice* external,
                const Eigen::Vector3d& tip0, SessionReport& rep) {
    LoopState s(cycle, loop, link, external, rep, plan_session(options), now_ns());
    begin_loop(s, tip0);
    // the status line spans homing, then the session
    SessionStatus status(options.homing_s + s.session.plan().session_length_s);
    while (!stop_requested()) {
      const std::int64_t now = now_ns();
      if (s.session.over(static_cast<double>(now) * 1e-9, cycle.homing(),
                         cycle.session_start_s())) {
        break;
      }
      run_cycle(s, now);
      loop.wait();
    }
    status.stop();
    end_loop(s);
  }

  /// What the report tells besides the session's figures (client/node/master_report.hpp).
  ReportContext report_context() const {
    return ReportContext{options,
                         binding,
                         scene_at_start,
                         master_session,
                         device_driver.ignored(),
                         TuningCounts{tuning->accepting(), tuning->received(), tuning->ignored(),
                                      tuning->dropped()}};
  }
};

MasterNode::MasterNode(const MasterOptions& options)
    : impl_options_(options), impl_(std::make_unique<Impl>(options)) {}
MasterNode::~MasterNode() = default;
int MasterNode::run() {
  double waited_s = 0.0;
  MasterOptions options = impl_options_;
  for (;;) {
    const int status = impl_->run(waited_s);
    if (status != kReconnect) return status;
    waited_s = impl_->waited_s;
    if (!impl_->options.quiet) {
      std::cerr << "teleop_master: no answer from a server over TCP for "
                << impl_->options.reconnect_s << " s: reconnecting\n";
    }
    // each new participant waits twice as long as the last: a handshake that is merely slow (DDS
    // Security's authentication on a loaded machine) is not cut off again and again
    options.reconnect_s *= 2.0;
    impl_.reset();
    impl_ = std::make_unique<Impl>(options);
  }
}

}  // namespace teleop::master
