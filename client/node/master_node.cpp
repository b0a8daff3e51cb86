#include "client/node/master_node.hpp"

#include <Eigen/Core>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <iostream>
#include <limits>
#include <mutex>
#include <thread>

#include "client/cycle/master_cycle.hpp"
#include "client/device/device_factory.hpp"
#include "client/device/device_idl.hpp"
#include "client/device/external_device.hpp"
#include "client/device/replay_device.hpp"
#include "client/device/simulated_device.hpp"
#include "client/metrics/hertz_reference.hpp"
#include "client/metrics/link_verdict.hpp"
#include "client/metrics/session_metrics.hpp"
#include "client/net/delay_channel.hpp"
#include "client/node/dds_slave_link.hpp"
#include "client/node/experiment_publisher.hpp"
#include "client/node/server_binding.hpp"
#include "client/node/server_health.hpp"
#include "client/node/tuning_endpoint.hpp"
#include "common/dds/async_writer.hpp"
#include "common/dds/contact_point.hpp"
#include "common/dds/endpoint.hpp"
#include "common/dds/rate_limited_publisher.hpp"
#include "common/dds/teleop_idl.hpp"
#include "common/util/clock.hpp"
#include "common/util/csv.hpp"
#include "common/util/exit_codes.hpp"
#include "common/util/files.hpp"
#include "common/util/json.hpp"
#include "common/util/progress.hpp"
#include "common/util/rate_loop.hpp"
#include "common/util/signals.hpp"
#include "common/util/version.hpp"
#include "teleop/idl/DevicePubSubTypes.h"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::master {

namespace {

constexpr std::size_t kCsvColumns = 38;

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
/// A log row; the count must match the header exactly (checked at compile time).
template <class... T>
std::array<double, kCsvColumns> csv_row(T... v) {
  static_assert(sizeof...(T) == kCsvColumns, "log row and header differ in length");
  return {static_cast<double>(v)...};
}
/// Force error RMS relative to the mean contact force (NaN without contact).
double relative_force_error(const SessionMetrics& m) {
  const double f = m.mean_contact_force_n();
  return f > 1e-9 ? m.force_error_rms_n() / f : std::nan("");
}

/// Internal status of Impl::run: make a new participant and wait again.
constexpr int kReconnect = -2;

/// Commands whose entry time is remembered for the loop-delay measurement.
constexpr std::uint64_t kEntryRing = 1 << 16;

}  // namespace

/// What the session measured, gathered once after the loop for the JSON and the printout.
struct SessionReport {
  double elapsed_s = 0.0;
  double session_s = 0.0;
  double wait_s = 0.0;
  std::uint64_t issued = 0;     // commands the cycle issued (into the injected forward channel)
  std::uint64_t in_flight = 0;  // of them, still held in the injected delay when it stopped
  std::uint64_t dropped = 0;    // of them, dropped by the injected channel (loss, burst, overflow)
  std::uint64_t sent = 0;       // written to DDS
  std::uint64_t received = 0;   // received by the server (across its restarts)
  std::uint64_t echoed = 0;
  std::uint64_t states_received = 0;
  std::uint64_t overruns = 0;
  std::uint64_t link_losses = 0;
  std::uint64_t stalls = 0;      // cycles that began kStallS or more after the last
  double longest_stall_s = 0.0;  // the longest such gap
  Summary rtt_ms;
  Summary loop_delay_ms;
  Summary jitter_us;
  ChannelReport forward;
  ChannelReport backward;
  // the server's side of the session (ServerStats and fault events, across restarts)
  std::uint64_t server_faults = 0;
  std::uint64_t server_watchdog_trips = 0;
  std::uint64_t server_overruns = 0;
  std::uint64_t server_rejected = 0;
  std::uint64_t server_restarts = 0;
  // ownership of the slave (docs/topics.md, "Ownership")
  std::uint64_t issued_before_owning = 0;  // commands sent while another master owned the slave
  bool refused = false;                    // refused the slave and never got it (exit status 4)
  bool refused_first = false;              // refused before it first owned the slave
  double waited_for_owner_s = 0.0;         // time spent refused, waiting for the slave
  std::uint64_t closing_cycles = 0;        // cycles of the final fade-out (after --samples)
  std::uint64_t releases_sent = 0;         // release commands written at the very end
  std::string owner_message;               // the server's word on who owns the slave
  // the loop's writes, handed to network threads (common/dds/async_writer.hpp)
  std::uint64_t commands_dropped = 0;  // replaced by a newer one (the network thread behind)
  std::uint64_t command_write_failures = 0;
  std::uint64_t states_replaced = 0;  // MasterState samples replaced by a newer one unwritten
  std::uint64_t events_dropped = 0;   // events that found the event ring full
  std::uint64_t write_failures = 0;   // refused by the middleware (states, events, device, tuning)
  // the device's silences (MasterCycle): the slave held, the cycles are not in the figures
  std::uint64_t driver_silences = 0;
  double driver_silent_s = 0.0;
  std::uint64_t experiment_writes = 0;  // teleop/experiment descriptions written
};

/// The link's figures of a session, as the verdict judges them.
inline LinkCounts link_counts(const SessionReport& rep) {
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

/// The session's verdict (client/metrics/link_verdict.hpp): the loop's, or "degraded" when the
/// link did not carry a loop that stayed stable; "refused" (exit status 4) when it never had the
/// slave (nothing was judged).
inline SessionVerdict session_verdict(const SessionMetrics& m, const SessionReport& rep,
                                      const std::string& scheme) {
  if (rep.refused && rep.issued == 0) {
    return SessionVerdict{"refused", "another master owns the slave", exit_code::kRefused};
  }
  return combine_verdict(m.verdict(), m.verdict_reason(),
                         judge_link(link_counts(rep), link_tolerance(scheme)));
}

/// One driver at a time on teleop/device_state: the first writer is the device until it has been
/// silent for kSilentNs; samples of any other writer meanwhile are ignored and counted (a second
/// driver or a second driving viewer must not move the master's hand). Called from the reader's
/// thread.
class DeviceDriverLatch {
 public:
  static constexpr std::int64_t kSilentNs = 100'000'000;
  bool accept(const eprosima::fastrtps::rtps::InstanceHandle_t& writer, std::int64_t now_ns) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (seen_ns_ == 0 || now_ns - seen_ns_ > kSilentNs) {
      driver_ = writer;
    } else if (writer != driver_) {
      ignored_.fetch_add(1);
      return false;
    }
    seen_ns_ = now_ns;
    return true;
  }
  std::uint64_t ignored() const { return ignored_.load(); }

 private:
  std::mutex mutex_;
  eprosima::fastrtps::rtps::InstanceHandle_t driver_;
  std::int64_t seen_ns_ = 0;
  std::atomic<std::uint64_t> ignored_{0};
};

/// The master's side of ownership during a run (watch_ownership()).
struct OwnershipWatch {
  bool refused = false;        // another master owns the slave: the cycle holds
  bool owned_once = false;     // this master has owned the slave in this session
  bool give_up = false;        // refused and not (or no longer) waiting: end the session
  bool refused_first = false;  // refused before it ever owned the slave
  double refused_at_s = 0.0;
  double waited_s = 0.0;
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
  dds::QueuedWriter<EventPubSubType, 64> event_writer;
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
  std::uint64_t event_seq = 0;
  std::unique_ptr<CsvWriter> log;
  // the server's health: ServerStats counters and fault events received during the session
  std::unique_ptr<dds::Reader<ServerStatsPubSubType>> stats_reader;
  std::unique_ptr<dds::Reader<EventPubSubType>> events_reader;
  dds::Mailbox<ServerStats> stats_box;
  std::atomic<std::int64_t> session_start_ns{std::numeric_limits<std::int64_t>::max()};
  std::atomic<std::uint64_t> server_fault_events{0};
  ServerHealth health;
  std::uint64_t stats_seen = 0;
  // ownership: the newest server event about this master's session
  std::mutex owner_event_mutex;
  std::string owner_event;
  bool second_server_reported = false;

  std::unique_ptr<TuningEndpoint> tuning;  // live tuning (teleop/tuning, teleop/tuning_status)
  std::unique_ptr<ExperimentPublisher> experiment;  // teleop/experiment, latched
  double waited_s = 0.0;  // time run() waited for the server before returning kReconnect
  bool tcp_client = false;

  explicit Impl(const MasterOptions& o)
      : options(o),
        participant(o.dds),
        command_writer(participant, dds::topics::kMasterCommand, dds::TopicQos::kStream),
        state_writer(participant, dds::topics::kMasterState, dds::TopicQos::kStream),
        event_writer(participant, dds::topics::kEvents, dds::TopicQos::kEventLog),
        state_views(participant,
                    {{dds::topics::kMasterStateView, dds::topics::kViewRateHz},
                     {dds::topics::kMasterStateMonitor, dds::topics::kMonitorRateHz}}) {
    dds::ProfileKind kind = dds::ProfileKind::kUdp;
    (void)dds::participant_qos(o.dds, &kind);
    tcp_client = kind == dds::ProfileKind::kTcp;
    Event
        event_prototype;  // the strings' capacity: the loop's copies into the ring do not allocate
    event_prototype.source(std::string(32, ' '));
    event_prototype.message(std::string(256, ' '));
    event_writer.prime(event_prototype);

    state_reader = std::make_unique<dds::Reader<SlaveStatePubSubType>>(
        participant, dds::topics::kSlaveState, dds::TopicQos::kStream,
        [this](const SlaveState& s, const eprosima::fastdds::dds::SampleInfo& info) {
          if (!binding.accept_state(info.sample_identity.writer_guid().guidPrefix,
                                    s.owner_session(), s.owner_active(), now_ns())) {
            return;  // another participant's: counted by the binding
          }
          states_received.fetch_add(1);
          mailbox.put(ReceivedState{s, now_ns()});
        });
    scene_reader = std::make_unique<dds::Reader<SceneDescriptionPubSubType>>(
        participant, dds::topics::kScene, dds::TopicQos::kLatched,
        [this](const SceneDescription& s, const eprosima::fastdds::dds::SampleInfo&) {
          scene_box.put(s);
        });
    stats_reader = std::make_unique<dds::Reader<ServerStatsPubSubType>>(
        participant, dds::topics::kServerStats, dds::TopicQos::kReliableStream,
        [this](const ServerStats& s, const eprosima::fastdds::dds::SampleInfo& info) {
          if (binding.accept(ServerBinding::kStats,
                             info.sample_identity.writer_guid().guidPrefix)) {
            stats_box.put(s);
          }
        });
    events_reader = std::make_unique<dds::Reader<EventPubSubType>>(
        participant, dds::topics::kEvents, dds::TopicQos::kEventLog,
        [this](const Event& e, const eprosima::fastdds::dds::SampleInfo& info) {
          // the server's events only from the server this master is bound to
          if (e.source() == "server" &&
              !binding.accept(ServerBinding::kEvent,
                              info.sample_identity.writer_guid().guidPrefix)) {
            return;
          }
          // a fault on the server during this session (the event log's history from before
          // the session arrives earlier and is not counted)
          if (e.source() == "server" &&
              e.kind() == static_cast<std::uint8_t>(sim::EventKind::kFault) &&
              now_ns() >= session_start_ns.load()) {
            server_fault_events.fetch_add(1);
          }
          // the server's word on this master's ownership (it names the session in hex)
          char mine[16];
          std::snprintf(mine, sizeof(mine), "0x%08x", master_session);
          if (e.source() == "server" &&
              e.kind() == static_cast<std::uint8_t>(sim::EventKind::kOwnership) &&
              std::strstr(e.message().c_str(), mine) != nullptr) {
            std::lock_guard<std::mutex> lock(owner_event_mutex);
            owner_event = e.message().c_str();
          }
        });
    tuning = std::make_unique<TuningEndpoint>(participant, master_session, o.accept_tuning);
    experiment = std::make_unique<ExperimentPublisher>(participant);
    if (o.device == "external") {
      device_command_writer = std::make_unique<dds::LatestWriter<DeviceCommandPubSubType>>(
          participant, "teleop/device_command", dds::TopicQos::kStream);
      device_state_reader = std::make_unique<dds::Reader<DeviceStatePubSubType>>(
          participant, "teleop/device_state", dds::TopicQos::kStream,
          [this](const DeviceState& s, const eprosima::fastdds::dds::SampleInfo& info) {
            if (device_driver.accept(info.publication_handle, now_ns())) device_box.put(s);
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

  /// Where the master's origin lands in the slave world: the flag's point, else where the tip
  /// touches the scene's target (common/dds/contact_point.hpp).
  Eigen::Vector3d contact_point(const SceneDescription* scene, const Eigen::Vector3d& tip) {
    if (options.has_contact_point) return options.contact_point_m;
    return dds::scene_contact_point(scene, tip);
  }

  OperatorScript make_device_script() const {
    if (options.script == "press-slip") {
      return press_slip_script(Eigen::Vector3d::Zero(), options.press_depth_m);
    }
    OperatorScript s;
    s.kind = parse_script_kind(options.script);
    return s;
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
    log = std::make_unique<CsvWriter>(
        options.log_csv,
        std::vector<std::string>{
            "t_s", "phase", "seq", "xm_x", "xm_y", "xm_z", "xs_x", "xs_y", "xs_z", "fe_x", "fe_y",
            "fe_z", "fm_x", "fm_y", "fm_z", "rtt_ms", "link_ok", "in_contact", "penetration_m",
            "energy_j", "safety_scale", "position_error_m", "deformation_m", "loop_delay_ms",
            "delay_injected_ms", "passivity_observer_j", "passivity_dissipated_j",
            // the device's own pose: the log
            // is a --device replay file
            "dev_x", "dev_y", "dev_z", "dev_qw", "dev_qx", "dev_qy", "dev_qz",
            // the samples of the summary's stiffness fits (docs/control.md, "Transparency")
            "slave_depth_m", "master_depth_m", "felt_force_n", "loading"});
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

  void log_row(const MasterCycle& cycle, double t_s, double rtt_ms, double loop_delay_ms) {
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
        (options.forward.delay_s + options.backward.delay_s) * 1e3, ps.observer_j, ps.dissipated_j,
        dev.position_m.x(), dev.position_m.y(), dev.position_m.z(), dev.orientation.w(),
        dev.orientation.x(), dev.orientation.y(), dev.orientation.z(), m.slave_depth_m,
        m.master_depth_m, m.felt_force_n,
        static_cast<double>(cycle.metrics().last_sample_loading()));
    log->row(vals.data(), vals.size());
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
    {
      std::lock_guard<std::mutex> lock(owner_event_mutex);
      rep.owner_message = owner_event;
    }
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
    SceneDescription scene;
    std::uint64_t scene_seen = 0;
    const bool have_scene = scene_box.take_if_newer(scene, scene_seen);
    const Eigen::Vector3d tip0 = detail::get3(link.newest_state().tip_position_m());

    // 2. device, controller, channels, safety, metrics (all allocation happens here)
    MasterCycleConfig cc;
    cc.controller = options.controller;
    cc.controller.workspace.offset_m = contact_point(have_scene ? &scene : nullptr, tip0);
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
    // a session id the server has not seen from an earlier master (it restarts its wave /
    // TDPA state when the id changes)
    cc.session_id = static_cast<std::uint32_t>(now_ns() / 1000) | 1u;
    std::unique_ptr<HapticDevice> device = make_device();
    device->configure();
    MasterCycle cycle(cc, *device, link);
    ExternalDevice* external = dynamic_cast<ExternalDevice*>(device.get());
    open_log();
    if (!options.quiet) {
      std::fprintf(stderr,
                   "teleop_master: server found after %.3f s (scene '%s'); %s, device %s, "
                   "script %s, contact point (%.3f, %.3f, %.3f) m, %s / %s\n",
                   wait_s, have_scene ? scene.name().c_str() : "?", cc.controller.scheme.c_str(),
                   options.device.c_str(), options.script.c_str(),
                   cc.controller.workspace.offset_m.x(), cc.controller.workspace.offset_m.y(),
                   cc.controller.workspace.offset_m.z(), options.forward.describe().c_str(),
                   options.backward.describe().c_str());
    }

    // 3. the haptic loop: homing (slave from where it is to the mapped script start, no force
    // rendered), then the session
    SessionReport rep;
    rep.wait_s = wait_s;
    if (have_scene) scene_at_start = scene;
    const DmaLatencyHold dma(options.realtime.dma_latency_us);
    if (!dma.problem().empty()) {
      std::fprintf(stderr, "teleop_master: warning: the cores may sleep deeply: %s\n",
                   dma.problem().c_str());
    }
    RateLoop loop(options.rate_hz, 65536,
                  static_cast<std::int64_t>(options.realtime.spin_us) * 1000);
    run_loop(cycle, loop, link, external, tip0, rep);
    cycle.stop();

    // 4. drain: late echoes and the server's final receive count
    const std::int64_t drain_start = now_ns();
    while (seconds_between(drain_start, now_ns()) < options.drain_s) {
      link.drain();
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    state_reader->stop();

    fill_report(cycle, link, loop, rep);
    // a file that could not be written is an error naming it, after everything else is out
    std::string write_error;
    try {
      if (log) log->close();
    } catch (const std::exception& e) {
      write_error = e.what();
    }
    if (!options.summary_json.empty()) write_summary_json(cycle, rep);
    if (!options.quiet) print_summary(cycle, rep);
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

  /// Ownership, once per cycle (see OwnershipWatch): a master refused the slave holds (renders
  /// nothing, commands nothing) and ends the session unless it waits; one that gets the slave
  /// after waiting re-homes. `grace_s`: how long this master's first commands may take to
  /// reach the server and its answer to come back.
  void watch_ownership(MasterCycle& cycle, const DdsSlaveLink& link, double now_s, double t0_s,
                       double grace_s, OwnershipWatch& w) {
    const DdsSlaveLink::Owner owner = link.owner();
    if (owner == DdsSlaveLink::Owner::kMine) {
      if (w.refused) {
        w.refused = false;
        w.waited_s += now_s - w.refused_at_s;
        cycle.hold(false);
        cycle.rehome(now_s, RehomeReason::kTakeover);
        event(static_cast<std::uint8_t>(sim::EventKind::kOwnership), 1,
              "got the slave after waiting " + std::to_string(now_s - w.refused_at_s) + " s",
              now_s - w.refused_at_s);
      }
      w.owned_once = true;
      return;
    }
    if (owner != DdsSlaveLink::Owner::kOther) return;
    if (!w.refused && (w.owned_once || now_s - t0_s > grace_s)) {
      w.refused = true;
      w.refused_first = !w.owned_once;
      w.refused_at_s = now_s;
      cycle.hold(true);
      char msg[160];
      std::snprintf(msg, sizeof(msg), "refused: the slave is owned by master session 0x%08x%s",
                    link.other_owner_session(),
                    options.wait_owner_s > 0 ? "; waiting for it" : "; no force rendered");
      event(static_cast<std::uint8_t>(sim::EventKind::kOwnership), 2, msg, 0.0);
      if (options.wait_owner_s <= 0) w.give_up = true;
    } else if (w.refused && now_s - w.refused_at_s > options.wait_owner_s) {
      w.give_up = true;
    }
  }

  /// What the loop's network threads replaced, dropped or saw refused (after the session).
  void count_network_threads(SessionReport& rep) {
    rep.commands_dropped = command_writer.dropped();
    rep.command_write_failures = command_writer.failures();
    rep.states_replaced = state_writer.replaced();
    event_writer.flush(0.5);
    rep.events_dropped = event_writer.dropped();
    experiment->flush(0.5);
    rep.experiment_writes = experiment->written();
    rep.write_failures = state_writer.failures() + event_writer.failures() +
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

  /// A cycle that begins this long after the previous one is a stall of this master's own loop
  /// (the process was stopped, starved or swapped out): the device held its last force meanwhile
  /// [s]. Far above any overrun of a loaded machine (tens of ms).
  static constexpr double kStallS = 0.2;

  /// A stall of the loop, detected from the clock: counted for the summary, published as an
  /// event, and the force fades out at the device's rate bound and back in over the link fade
  /// (SafetyLayer::fade_in) instead of carrying on from where it froze.
  void check_stall(MasterCycle& cycle, double now_s, double prev_s, SessionReport& rep) {
    if (prev_s < 0.0 || now_s - prev_s < kStallS) return;
    const double gap_s = now_s - prev_s;
    ++rep.stalls;
    rep.longest_stall_s = std::max(rep.longest_stall_s, gap_s);
    cycle.safety().fade_in();
    char msg[96];
    std::snprintf(msg, sizeof msg, "haptic loop stalled for %.3f s: force faded out and back in",
                  gap_s);
    event(static_cast<std::uint8_t>(sim::EventKind::kWatchdog), 1, msg, gap_s);
    if (!options.quiet) std::cerr << "teleop_master: " << msg << "\n";
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
      if (log) log_row(cycle, now_s - t0_s, link.last_rtt_ms(), std::nan(""));
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
    return std::max<std::uint64_t>(health.faults.total(), server_fault_events.load());
  }

  /// The haptic loop until the session length, the sample limit or a stop signal.
  void run_loop(MasterCycle& cycle, RateLoop& loop, DdsSlaveLink& link, ExternalDevice* external,
                const Eigen::Vector3d& tip0, SessionReport& rep) {
    std::vector<double> entry_time_s(kEntryRing, 0.0);
    std::uint64_t last_used_seq = 0;
    SampleWindow loop_delay_ms(1 << 20);
    double last_loop_delay_ms = std::nan("");
    MasterState ms;
    std::uint64_t cycles = 0;
    bool was_link_lost = false;
    double prev_cycle_s = -1.0;
    const auto state_every = std::max<std::uint64_t>(
        1, static_cast<std::uint64_t>(std::llround(options.rate_hz / options.state_rate_hz)));
    const double session_length =
        options.duration_s > 0 ? options.duration_s
                               : (options.device == "simulated"
                                      ? std::max(2.0, script_duration_s(make_device_script()) + 1.0)
                                      : 10.0);
    DeviceState device_sample;
    std::uint64_t device_seen = 0;
    const std::int64_t t0 = now_ns();
    const double t0_s = static_cast<double>(t0) * 1e-9;
    if (wants_thread_setup(options.realtime)) {
      const std::string problem = make_thread_realtime(options.realtime);
      if (!problem.empty()) {
        std::cerr << "teleop_master: warning: the haptic loop stays a normal thread: " << problem
                  << "\n";
      }
    }
    update_health();  // the baseline: the server's counts from before this session
    session_start_ns.store(t0);
    cycle.start_homing(t0_s, tip0, options.homing_s);
    tuning->publish_status(cycle, t0);
    experiment->begin(cycle, master_session, options.name, options.device, options.rate_hz);
    // made once: the loop passes it by reference every cycle without building a std::function
    const std::function<void(std::uint8_t, const std::string&)> report_tuning =
        [this](std::uint8_t severity, const std::string& msg) {
          event(static_cast<std::uint8_t>(sim::EventKind::kTuning), severity, msg, 0.0);
          if (!options.quiet && severity == 0) std::cerr << "teleop_master: " << msg << "\n";
        };
    std::uint64_t faults_seen = 0;
    OwnershipWatch owner;
    SessionStatus status(options.homing_s + session_length);  // homing, then the session
    const double grace_s = 0.5 + 2.0 * (options.forward.delay_s + options.backward.delay_s);

    while (!stop_requested()) {
      const std::int64_t now = now_ns();
      const double now_s = static_cast<double>(now) * 1e-9;
      if (options.samples > 0 && cycles >= options.samples) break;
      if (owner.give_up) break;
      if (!cycle.homing() && now_s - cycle.session_start_s() >= session_length) break;
      ++cycles;

      if (external && device_box.take_if_newer(device_sample, device_seen)) {
        external->on_sample(from_idl(device_sample));
      }
      if (external && !device_foreign_reported && device_driver.ignored() > 0) {
        device_foreign_reported = true;
        event(static_cast<std::uint8_t>(sim::EventKind::kOwnership), 1,
              "ignoring teleop/device_state from a second driver while the first one is live", 0.0);
      }
      tuning->poll(cycle, now_s, now, report_tuning);
      check_stall(cycle, now_s, prev_cycle_s, rep);
      prev_cycle_s = now_s;
      cycle.step(now_s);
      entry_time_s[cycle.command_seq() % kEntryRing] = now_s;
      if (cycle.sample_arrived()) {
        // loop delay: the command entered the forward channel -> its echo reaches the controller
        const std::uint64_t echoed = cycle.slave_at_master().command_seq;
        const std::uint64_t seq = cycle.command_seq();
        if (echoed > last_used_seq && echoed < seq && echoed + kEntryRing > seq) {
          last_used_seq = echoed;
          last_loop_delay_ms = (now_s - entry_time_s[echoed % kEntryRing]) * 1e3;
          loop_delay_ms.record(last_loop_delay_ms);
          experiment->record_loop_delay(last_loop_delay_ms);
        }
      }
      if (external && device_command_writer) {
        DeviceCommand dc = to_idl(external->next_command(), now);
        device_command_writer->write(dc);
      }
      watch_ownership(cycle, link, now_s, t0_s, grace_s, owner);
      report_second_server();
      cycle.finish(now_s);
      experiment->update(cycle, now_s, now);
      // a session whose slave faulted is never stable
      if (const std::uint64_t faults = update_health(); faults > faults_seen) {
        faults_seen = faults;
        cycle.metrics().mark_unstable("the slave faulted on the server", now_s - t0_s);
      }
      if (cycle.safety().link_lost() && !was_link_lost) ++rep.link_losses;
      was_link_lost = cycle.safety().link_lost();
      sim::SimEvent se;
      while (cycle.safety().events().pop(se)) {
        event(static_cast<std::uint8_t>(se.kind), static_cast<std::uint8_t>(se.severity),
              se.message, se.value);
      }
      if (cycles % state_every == 0) publish_state(cycle, cycles, now, link.last_rtt_ms(), ms);
      if (log) log_row(cycle, now_s - t0_s, link.last_rtt_ms(), last_loop_delay_ms);
      loop.wait();
    }
    status.stop();
    const double end_s = static_cast<double>(now_ns()) * 1e-9;
    rep.elapsed_s = end_s - t0_s;
    rep.session_s = cycle.session_start_s() < 0 ? 0.0 : end_s - cycle.session_start_s();
    rep.loop_delay_ms = summarize(loop_delay_ms.snapshot());
    rep.refused = owner.give_up;
    rep.refused_first = owner.refused_first;
    rep.waited_for_owner_s = owner.waited_s + (owner.refused ? end_s - owner.refused_at_s : 0.0);
    rep.driver_silences = cycle.driver_silences();
    rep.driver_silent_s = cycle.driver_silent_s(end_s);
    rep.closing_cycles = close_session(cycle, loop, link, t0_s);
    rep.releases_sent = link.releases_sent();
  }

  /// Hertz for the scene's first deformable body with a material, at the deepest travel.
  HertzReference hertz_for_session(const SessionMetrics& metrics) const {
    double gravity = 0.0;
    for (double g : scene_at_start.gravity_mps2()) gravity += g * g;
    gravity = std::sqrt(gravity);
    for (const SceneObject& o : scene_at_start.objects()) {
      if (o.kind() != OBJECT_DEFORMABLE_MESH || !(o.youngs_modulus_pa() > 0.0)) continue;
      const LoadingFit& fit = metrics.environment_fit();
      const bool fitted = std::isfinite(metrics.environment_stiffness_n_per_m());
      return hertz_reference(o.youngs_modulus_pa(), o.poisson_ratio(), o.size_m()[0],
                             scene_at_start.tip_radius_m(), o.mass_kg() * gravity,
                             metrics.max_slave_depth_m(), fitted ? fit.x_min : 0.0,
                             fitted ? fit.x_max : 0.0);
    }
    return HertzReference{};
  }

  void write_summary_json(const MasterCycle& cycle, const SessionReport& rep) const {
    const SessionMetrics& metrics = cycle.metrics();
    const SessionVerdict verdict = session_verdict(metrics, rep, cycle.config().controller.scheme);
    const HertzReference hz = hertz_for_session(metrics);
    OrderedJson out;
    out["version"] = version_string();
    out["hertz"] = {{"valid", hz.valid},
                    {"travel_m", json_number(hz.travel_m)},
                    {"force_n", json_number(hz.force_n)},
                    {"tangent_n_per_m", json_number(hz.tangent_n_per_m)},
                    {"secant_n_per_m", json_number(hz.secant_n_per_m)},
                    {"fit_from_m", json_number(hz.fit_from_m)},
                    {"fit_to_m", json_number(hz.fit_to_m)},
                    {"fit_n_per_m", json_number(hz.fit_n_per_m)}};
    out["duration_s"] = json_number(rep.elapsed_s);
    out["session_s"] = json_number(rep.session_s);
    out["rate_hz"] = json_number(options.rate_hz);
    out["scheme"] = cycle.config().controller.scheme;
    out["device"] = options.device;
    out["device_samples_ignored"] = device_driver.ignored();
    out["script"] = options.script;
    add_link_fields(out, rep);
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
    add_safety_fields(out, cycle, rep);
    out["experiment_writes"] = rep.experiment_writes;
    out["tuning"] = tuning_fields(cycle);
    out["ownership"] = {{"session", master_session},
                        {"refused", rep.refused},
                        {"issued_before_owning", rep.issued_before_owning},
                        {"waited_s", json_number(rep.waited_for_owner_s)},
                        {"server_says", rep.owner_message}};
    write_text_file(options.summary_json, json_document(out));
  }

  /// The summary's counts of the command link, the server's and the network threads'.
  void add_link_fields(OrderedJson& out, const SessionReport& rep) const {
    out["issued"] = rep.issued;
    out["dropped_by_channel"] = rep.dropped;
    out["sent"] = rep.sent;
    out["received"] = rep.received;
    out["in_flight"] = rep.in_flight;
    out["lost"] = lost_commands(link_counts(rep));
    out["server"] = {{"faults", rep.server_faults},
                     {"watchdog_trips", rep.server_watchdog_trips},
                     {"overruns", rep.server_overruns},
                     {"rejected", rep.server_rejected},
                     {"restarts", rep.server_restarts}};
    out["server_binding"] = binding_fields();
    out["network_threads"] = {{"commands_dropped", rep.commands_dropped},
                              {"command_write_failures", rep.command_write_failures},
                              {"states_replaced", rep.states_replaced},
                              {"events_dropped", rep.events_dropped},
                              {"write_failures", rep.write_failures}};
  }

  /// The summary's round trip, loop delay and jitter, overruns, link losses and stalls.
  static void add_timing_fields(OrderedJson& out, const SessionReport& rep) {
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
  void add_safety_fields(OrderedJson& out, const MasterCycle& cycle,
                         const SessionReport& rep) const {
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
    out["driver"] = {{"timeout_ms", json_number(options.driver_timeout_s * 1e3)},
                     {"silences", rep.driver_silences},
                     {"silent_s", json_number(rep.driver_silent_s)},
                     {"live_s", json_number(std::max(0.0, rep.session_s - rep.driver_silent_s))},
                     {"figures", "over the time the device was live"}};
  }

  /// {"server": prefix, "bound":.., "rebinds":.., "foreign": {"states":.., "stats":..,
  /// "events":..}, "first_foreign": prefix}: which server this master believed, and what it
  /// ignored from other participants.
  OrderedJson binding_fields() const {
    return {{"server", binding.server()},
            {"bound", binding.bound()},
            {"rebinds", binding.rebinds()},
            {"foreign",
             {{"states", binding.foreign(ServerBinding::kState)},
              {"stats", binding.foreign(ServerBinding::kStats)},
              {"events", binding.foreign(ServerBinding::kEvent)}}},
            {"first_foreign", binding.first_foreign()}};
  }

  /// The summary's lines on the server binding and the loop's network threads.
  std::string binding_lines(const SessionReport& rep) const {
    char buf[512];
    std::snprintf(
        buf, sizeof(buf),
        "  server binding  %s %s (%llu moves); ignored from other participants: %llu states, "
        "%llu stats, %llu server events%s%s\n"
        "  network thread  commands: %llu replaced by a newer one, %llu refused; states: %llu "
        "replaced; events: %llu dropped; other writes refused: %llu\n",
        binding.bound() ? "bound to" : "never bound, followed", binding.server().c_str(),
        static_cast<unsigned long long>(binding.rebinds()),
        static_cast<unsigned long long>(binding.foreign(ServerBinding::kState)),
        static_cast<unsigned long long>(binding.foreign(ServerBinding::kStats)),
        static_cast<unsigned long long>(binding.foreign(ServerBinding::kEvent)),
        binding.foreign_total() > 0 ? " (first from " : "",
        binding.foreign_total() > 0 ? (binding.first_foreign() + ")").c_str() : "",
        static_cast<unsigned long long>(rep.commands_dropped),
        static_cast<unsigned long long>(rep.command_write_failures),
        static_cast<unsigned long long>(rep.states_replaced),
        static_cast<unsigned long long>(rep.events_dropped),
        static_cast<unsigned long long>(rep.write_failures));
    std::string lines = buf;
    if (options.device == "external") {
      // teleop/device_state: one driver at a time (DeviceDriverLatch)
      lines += "  device driver   " + std::to_string(device_driver.ignored()) +
               " teleop/device_state samples of a second driver ignored\n";
    }
    return lines;
  }

  /// The summary's line on the device's silences (MasterCycle::check_driver).
  std::string driver_line(const MasterCycle& cycle, const SessionReport& rep) const {
    char buf[400];
    if (rep.driver_silences == 0) {
      std::snprintf(buf, sizeof(buf),
                    "  device          live the whole session (never without a valid reading "
                    "for over %.0f ms)\n",
                    options.driver_timeout_s * 1e3);
      return buf;
    }
    std::snprintf(buf, sizeof(buf),
                  "  device          live %.2f s of %.2f s; silent %llu times, %.2f s in all (no "
                  "valid reading for over %.0f ms: the slave held, the force faded; not in the "
                  "figures), came back %llu times\n",
                  std::max(0.0, rep.session_s - rep.driver_silent_s), rep.session_s,
                  static_cast<unsigned long long>(rep.driver_silences), rep.driver_silent_s,
                  options.driver_timeout_s * 1e3,
                  static_cast<unsigned long long>(cycle.rehomes(RehomeReason::kDriverBack)));
    return buf;
  }

  /// {"accepting":..,"received":..,"applied":..,"rejected":..,"ignored":..,"dropped":..,
  ///  "in_force": {...}}: live tuning over the session.
  OrderedJson tuning_fields(const MasterCycle& cycle) const {
    const TuningValues& v = cycle.tuning().current();
    OrderedJson in_force = {{"master_stiffness_n_per_m", json_number(v.master_stiffness_n_per_m)},
                            {"master_damping_ns_per_m", json_number(v.master_damping_ns_per_m)},
                            {"force_gain", json_number(v.force_gain)},
                            {"slave_stiffness_n_per_m", json_number(v.slave_stiffness_n_per_m)},
                            {"forward_delay_ms", json_number(v.forward_delay_s * 1e3)},
                            {"backward_delay_ms", json_number(v.backward_delay_s * 1e3)}};
    return {{"accepting", tuning->accepting()},    {"received", tuning->received()},
            {"applied", cycle.tunings_accepted()}, {"rejected", cycle.tunings_rejected()},
            {"ignored", tuning->ignored()},        {"dropped", tuning->dropped()},
            {"in_force", std::move(in_force)}};
  }

  void print_summary(const MasterCycle& cycle, const SessionReport& rep) const {
    const SessionMetrics& metrics = cycle.metrics();
    const SafetyLayer& safety = cycle.safety();
    const ChannelReport& fwd = rep.forward;
    const ChannelReport& bwd = rep.backward;
    const Summary& r = rep.rtt_ms;
    const Summary& ld = rep.loop_delay_ms;
    const Summary& j = rep.jitter_us;
    const std::uint64_t lost = lost_commands(link_counts(rep));
    const std::uint64_t left = rep.issued - rep.in_flight;
    const double rel = relative_force_error(metrics);
    char rel_buf[32];
    std::snprintf(rel_buf, sizeof(rel_buf), "%.0f%%", 100.0 * rel);
    const std::string relative = std::isfinite(rel) ? rel_buf : "no contact: -";
    char own_buf[160];
    std::snprintf(own_buf, sizeof(own_buf), "session 0x%08x%s", master_session,
                  rep.refused ? ": REFUSED, another master owns the slave"
                              : (rep.issued_before_owning > 0 ? ": got the slave after waiting"
                                                              : ": owned the slave"));
    std::string ownership = own_buf;
    if (rep.issued_before_owning > 0 || rep.refused) {
      ownership += " (" + std::to_string(rep.issued_before_owning) +
                   " commands sent while refused, " + std::to_string(rep.waited_for_owner_s) +
                   " s)";
    }
    std::string tuning_line;
    if (tuning->accepting()) {
      const TuningValues& v = cycle.tuning().current();
      char buf[256];
      std::snprintf(buf, sizeof(buf),
                    "  tuning          %llu requests: %llu applied, %llu rejected; in force K_pm "
                    "%.0f N/m, B_m %.2f N s/m, K_f %.2f, K_ps %.0f N/m, delay %.1f / %.1f ms\n",
                    static_cast<unsigned long long>(tuning->received()),
                    static_cast<unsigned long long>(cycle.tunings_accepted()),
                    static_cast<unsigned long long>(cycle.tunings_rejected()),
                    v.master_stiffness_n_per_m, v.master_damping_ns_per_m, v.force_gain,
                    v.slave_stiffness_n_per_m, v.forward_delay_s * 1e3, v.backward_delay_s * 1e3);
      tuning_line = buf;
    }
    tuning_line += binding_lines(rep) + driver_line(cycle, rep);
    const SessionVerdict verdict = session_verdict(metrics, rep, cycle.config().controller.scheme);
    const std::string& reason = verdict.reason;
    char text[8192];
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
        "  loop jitter     p50 %.1f us  p99 %.1f us  (%llu overruns)\n"
        "  tracking        position error RMS %.2f mm, max %.2f mm\n"
        "  force           max rendered %.2f N, force error RMS %.3f N (%s of the mean "
        "contact force), contact %.2f s, mean contact force %.2f N\n"
        "  transparency    over the %.2f s the device was live: free space %.3f N mean, %.3f N "
        "p99, %.3f N max; in contact felt %.2f x "
        "the environment's force (RMS %.3f N), stiffness felt %.0f N/m against %.0f N/m (%.2f; "
        "loading fit F = k x + b, b %.2f N against %.2f N)\n"
        "%s"
        "  passivity       energy at the master port %.4f J (min %.4f J)\n"
        "  safety          %s%s, link losses %llu, loop stalls %llu (longest %.3f s), re-homed "
        "%llu times (link back %llu, slave "
        "restart %llu, takeover %llu); force change at most %.3f N per cycle (bound %.0f N/s, "
        "held to it in %llu cycles)\n"
        "  ownership       %s\n"
        "%s"
        "  server          %llu faults, %llu watchdog trips, %llu overruns, %llu commands "
        "rejected, %llu restarts\n"
        "  verdict         %s%s%s\n",
        cycle.config().controller.scheme.c_str(), options.device.c_str(), options.script.c_str(),
        rep.elapsed_s, rep.session_s, options.rate_hz, static_cast<unsigned long long>(rep.issued),
        static_cast<unsigned long long>(rep.received), static_cast<unsigned long long>(lost),
        left ? 100.0 * static_cast<double>(lost) / static_cast<double>(left) : 0.0,
        static_cast<unsigned long long>(rep.dropped), static_cast<unsigned long long>(rep.sent),
        static_cast<unsigned long long>(rep.in_flight), options.forward.describe().c_str(),
        fwd.delay_mean_ms, fwd.delay_p99_ms, 100.0 * fwd.loss_fraction,
        options.backward.describe().c_str(), bwd.delay_mean_ms, bwd.delay_p99_ms,
        100.0 * bwd.loss_fraction, r.p50, r.p99, r.max, r.count, ld.p50, ld.p99, j.p50, j.p99,
        static_cast<unsigned long long>(rep.overruns), metrics.position_error_rms_m() * 1e3,
        metrics.position_error_max_m() * 1e3, metrics.max_device_force_n(),
        metrics.force_error_rms_n(), relative.c_str(), metrics.contact_time_s(),
        metrics.mean_contact_force_n(), std::max(0.0, rep.session_s - rep.driver_silent_s),
        metrics.free_force_mean_n(), metrics.free_force_p99_n(), metrics.free_force_max_n(),
        metrics.felt_force_ratio(), metrics.felt_force_error_rms_n(),
        metrics.felt_stiffness_n_per_m(), metrics.environment_stiffness_n_per_m(),
        metrics.stiffness_ratio(), metrics.felt_fit().offset(), metrics.environment_fit().offset(),
        hertz_line(hertz_for_session(metrics), metrics.felt_stiffness_n_per_m(),
                   metrics.environment_stiffness_n_per_m())
            .c_str(),
        metrics.energy_j(), metrics.energy_min_j(), safety.cut() ? "CUT: " : "ok",
        safety.cut() ? safety.cut_reason() : "", static_cast<unsigned long long>(rep.link_losses),
        static_cast<unsigned long long>(rep.stalls), rep.longest_stall_s,
        static_cast<unsigned long long>(cycle.rehomes()),
        static_cast<unsigned long long>(cycle.rehomes(RehomeReason::kLinkBack)),
        static_cast<unsigned long long>(cycle.rehomes(RehomeReason::kSlaveRestart)),
        static_cast<unsigned long long>(cycle.rehomes(RehomeReason::kTakeover)),
        safety.max_step_n(), cycle.device_spec().max_force_rate_n_per_s,
        static_cast<unsigned long long>(safety.rate_limited_cycles()), ownership.c_str(),
        tuning_line.c_str(), static_cast<unsigned long long>(rep.server_faults),
        static_cast<unsigned long long>(rep.server_watchdog_trips),
        static_cast<unsigned long long>(rep.server_overruns),
        static_cast<unsigned long long>(rep.server_rejected),
        static_cast<unsigned long long>(rep.server_restarts), verdict.name.c_str(),
        reason.empty() ? "" : " - ", reason.c_str());
    std::fputs(nan_as_na(text).c_str(), stdout);
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
