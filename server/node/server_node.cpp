#include "server/node/server_node.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <mutex>
#include <vector>

#include "common/dds/async_writer.hpp"
#include "common/dds/endpoint.hpp"
#include "common/dds/event_publisher.hpp"
#include "common/dds/guid_text.hpp"
#include "common/dds/log_summary.hpp"
#include "common/dds/rate_limited_publisher.hpp"
#include "common/dds/teleop_idl.hpp"
#include "common/util/clock.hpp"
#include "common/util/files.hpp"
#include "common/util/json.hpp"
#include "common/util/prewarm.hpp"
#include "common/util/rate_loop.hpp"
#include "common/util/signals.hpp"
#include "common/util/stats.hpp"
#include "common/util/version.hpp"
#include "server/node/command_gate.hpp"
#include "server/node/mesh_publisher.hpp"
#include "server/node/scene_objects.hpp"
#include "server/node/server_cycle.hpp"
#include "server/node/state_message.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::server {

namespace {

/// Newest accepted command and when it arrived (server clock).
struct ReceivedCommand {
  MasterCommand cmd;
  std::int64_t receive_ns = 0;
};

/// The reader thread's view of ownership for the loop: a snapshot and the messages of notable
/// decisions, under a mutex the loop only try-locks (it never waits for the reader).
struct OwnerMailbox {
  static constexpr std::size_t kMessages = 8;
  std::mutex mutex;
  OwnerReport report;
  std::int64_t owner_last_ns = 0;  // the owner's newest command [server ns]
  bool owned = false;
  std::uint64_t changes = 0;
  std::array<std::array<char, 256>, kMessages> messages{};
  std::array<double, kMessages> values{};
  std::array<sim::Severity, kMessages> severities{};
  std::array<sim::EventTags, kMessages> tags{};
  std::size_t pending = 0;
};

WriterId writer_id(const eprosima::fastrtps::rtps::InstanceHandle_t& h) {
  WriterId w;
  for (std::size_t i = 0; i < w.bytes.size(); ++i) w.bytes[i] = h.value[i];
  return w;
}

}  // namespace

struct ServerNode::Impl {
  ServerOptions options;
  const sim::WorldModel& model;
  ServerCycle cycle;
  dds::Participant participant;
  // the step loop's writes go through network threads: the loop never waits on the network
  dds::QueuedWriter<SlaveStatePubSubType, 64> state_writer;
  dds::Writer<SceneDescriptionPubSubType> scene_writer;
  dds::EventPublisher event_publisher;
  dds::Writer<MeshTopologyPubSubType> topology_writer;
  dds::Writer<MeshFramePubSubType> frame_writer;
  dds::Writer<MeshFramePubSubType> frame_monitor_writer;
  // observers' rate-limited copies of the state and the 1 Hz stats: written from their own
  // threads, so the loop's cost does not grow with the number of observers (docs/topics.md)
  dds::RateLimitedPublisher<SlaveStatePubSubType> state_views;
  dds::RateLimitedPublisher<ServerStatsPubSubType> stats_publisher;
  CommandCounters counters;
  dds::Mailbox<ReceivedCommand> mailbox;
  // reader-thread state: the edge (field checks, ownership, the owner's sequence / passivity)
  CommandGate gate;
  OwnerMailbox owner_box;
  // loop-side copy of the ownership snapshot
  OwnerReport owner;
  std::int64_t owner_last_ns = 0;
  bool owned = false;
  std::uint64_t ownership_changes = 0;
  std::unique_ptr<dds::Reader<MasterCommandPubSubType>> command_reader;
  // loop state
  sim::EventQueue events;
  std::uint32_t command_session = 0;  // MasterCommand.master_session of the newest command fed
  std::uint64_t faults = 0;
  SampleWindow step_us{1 << 16};
  SampleWindow step_us_all{1 << 20};
  // where a step's time goes, over the session: collision, deformable bodies, slave, and
  // packing + writing the state and offering the observers' copies (publish)
  SampleWindow collision_us{1 << 19}, deformable_us{1 << 19}, slave_us{1 << 19},
      publish_us{1 << 19};
  std::vector<double> scratch;
  std::uint64_t last_rejected = 0;
  std::int64_t last_reject_event_ns = 0;
  std::int64_t last_stats_ns = 0;
  std::uint64_t last_stats_steps = 0;
  bool over_observer_limit = false;
  int observers_max_seen = 0;

  Impl(const ServerOptions& o, const sim::WorldModel& m)
      : options(o),
        model(m),
        cycle(m, 1.0 / o.rate_hz, o.command_timeout_s),
        participant(o.dds),
        state_writer(participant, dds::topics::kSlaveState),
        scene_writer(participant, dds::topics::kScene),
        event_publisher(participant, "server"),
        topology_writer(participant, dds::topics::kMeshTopology),
        frame_writer(participant, dds::topics::kMeshFrame),
        frame_monitor_writer(participant, dds::topics::kMeshFrameMonitor),
        state_views(participant, {{dds::topics::kSlaveStateView, dds::topics::kViewRateHz},
                                  {dds::topics::kSlaveStateMonitor, dds::topics::kMonitorRateHz}}),
        stats_publisher(participant, {{dds::topics::kServerStats, 0.0}}),
        gate(m.workspace_min_m, m.workspace_max_m,
             static_cast<std::int64_t>(std::llround(o.owner_timeout_s * 1e9))) {
    scratch.reserve(step_us.capacity());
    SlaveState state_prototype;  // the sequences' capacity: the loop's copies do not allocate
    state_prototype.joint_position_rad().assign(16, 0.0);
    state_prototype.joint_velocity_radps().assign(16, 0.0);
    state_prototype.joint_torque_nm().assign(16, 0.0);
    state_writer.prime(state_prototype);
    command_reader = std::make_unique<dds::Reader<MasterCommandPubSubType>>(
        participant, dds::topics::kMasterCommand,
        [this](const MasterCommand& c, const eprosima::fastdds::dds::SampleInfo& info) {
          on_command(c, info);
        });
  }

  ~Impl() { command_reader->stop(); }

  /// Reader thread: the edge (command_gate.hpp), counted; the newest command that passes goes
  /// to the loop's mailbox, ownership changes to the owner mailbox.
  void on_command(const MasterCommand& c, const eprosima::fastdds::dds::SampleInfo& info) {
    const std::int64_t now = now_ns();
    const bool pass = gate.pass(c, writer_id(info.publication_handle), now);
    const GateCounts& g = gate.counts();
    counters.received.store(g.received);
    counters.accepted.store(g.accepted);
    counters.rejected_nan.store(g.rejected_nan);
    counters.rejected_workspace.store(g.rejected_workspace);
    counters.rejected_stale.store(g.rejected_stale);
    counters.rejected_passivity.store(g.rejected_passivity);
    counters.refused_owner.store(g.refused_owner);
    {
      const Ownership& own = gate.ownership();
      std::lock_guard<std::mutex> lock(owner_box.mutex);
      owner_box.report.session = own.session();
      owner_box.report.first_seq = own.owner_first_seq();
      owner_box.report.received = own.owner_received();
      owner_box.owned = own.owned();
      owner_box.owner_last_ns = own.owner_last_ns();
      owner_box.changes = own.changes();
      if (gate.ownership().notable() && owner_box.pending < OwnerMailbox::kMessages) {
        std::snprintf(owner_box.messages[owner_box.pending].data(), 256, "%s", own.message());
        owner_box.values[owner_box.pending] = static_cast<double>(own.changes());
        owner_box.tags[owner_box.pending] = own.tags();
        owner_box.severities[owner_box.pending] =
            gate.admit() == Admit::kRefused || gate.admit() == Admit::kTakenOver
                ? sim::Severity::kWarning
                : sim::Severity::kInfo;
        ++owner_box.pending;
      }
    }
    if (pass) mailbox.put(ReceivedCommand{c, now});
  }

  std::uint64_t rejected() const {
    return counters.rejected_nan.load() + counters.rejected_workspace.load() +
           counters.rejected_stale.load() + counters.rejected_passivity.load() +
           counters.refused_owner.load();
  }

  void publish_event(const sim::SimEvent& e) {
    event_publisher.publish(e);
    if (!options.quiet && e.severity != sim::Severity::kInfo) {
      std::cerr << "teleop_server: event: " << e.message << "\n";
    }
  }

  void publish_scene() {
    for (MeshTopology& t : mesh_topologies(model)) topology_writer.write(t);
    SceneDescription d = describe_scene(model, cycle.data(), options.rate_hz);
    scene_writer.write(d);
    sim::SimEvent start{};
    std::snprintf(start.message, sizeof(start.message),
                  "server started: scene '%s', %.0f Hz, domain %d, profile %s, participant %s",
                  model.name.c_str(), options.rate_hz, options.dds.domain,
                  options.dds.profile.c_str(),
                  dds::guid_prefix_text(participant.raw()->guid().guidPrefix).c_str());
    publish_event(start);
    if (!options.quiet) std::cerr << "teleop_server: " << start.message << "\n";
    for (const sim::DeformableBodyModel& b : model.bodies) {
      if (b.auto_summary.empty()) {  // a body fixed by the scene: what runs it, kernel included
        const sim::deformable::DeformableParams& p = b.body.params;
        const bool simd = p.kernel == sim::deformable::KernelKind::kSimd;
        sim::SimEvent body{};
        std::snprintf(
            body.message, sizeof(body.message),
            "deformable %d: %s %s, kernel %s%s, %d nodes%s, %d sub-step(s) per step", b.object_id,
            sim::deformable::to_string(p.model), sim::deformable::to_string(p.integrator),
            sim::deformable::to_string(p.kernel),
            simd ? (sim::deformable::simd_kernel_vectorised() ? " (AVX2)" : " (portable)") : "",
            b.body.state_node_count(),
            p.model == sim::deformable::ModelKind::kFem
                ? (" (" + std::to_string(b.body.node_count) + " on the surface), " +
                   std::to_string(b.body.fem.tet_count) + " tetrahedra")
                      .c_str()
                : "",
            b.body.substeps_for(1.0 / options.rate_hz));
        body.value = static_cast<double>(b.object_id);
        publish_event(body);
        if (!options.quiet) std::cerr << "teleop_server: " << body.message << "\n";
        continue;
      }
      sim::SimEvent choice{};  // the automatic model's choice
      std::snprintf(choice.message, sizeof(choice.message), "deformable %d %s", b.object_id,
                    b.auto_summary.c_str());
      choice.value = static_cast<double>(b.object_id);
      publish_event(choice);
      if (!options.quiet) std::cerr << "teleop_server: " << b.auto_report << "\n";
    }
  }

  /// Loop: the reader's ownership snapshot (when its mutex is free) and its events; whether
  /// the owner is active is judged on the loop's clock.
  void take_owner(std::int64_t t_ns) {
    std::unique_lock<std::mutex> lock(owner_box.mutex, std::try_to_lock);
    if (lock.owns_lock()) {
      owner = owner_box.report;
      owned = owner_box.owned;
      owner_last_ns = owner_box.owner_last_ns;
      ownership_changes = owner_box.changes;
      for (std::size_t i = 0; i < owner_box.pending; ++i) {
        events.push(sim::EventKind::kOwnership, owner_box.severities[i], cycle.output().sim_time_s,
                    owner_box.values[i], owner_box.messages[i].data(), owner_box.tags[i]);
      }
      owner_box.pending = 0;
    }
    owner.active = owned && t_ns - owner_last_ns <= gate.ownership().timeout_ns();
  }

  /// Rejected commands: one event per second at most, with the counts so far.
  void report_rejections(std::int64_t t_ns) {
    const std::uint64_t r = rejected();
    if (r == last_rejected || t_ns - last_reject_event_ns <= 1'000'000'000LL) return;
    char msg[sizeof(sim::SimEvent::message)];
    std::snprintf(msg, sizeof(msg),
                  "rejected commands so far: %llu non-finite, %llu outside workspace, "
                  "%llu stale, %llu bad passivity, %llu not the owner's",
                  static_cast<unsigned long long>(counters.rejected_nan.load()),
                  static_cast<unsigned long long>(counters.rejected_workspace.load()),
                  static_cast<unsigned long long>(counters.rejected_stale.load()),
                  static_cast<unsigned long long>(counters.rejected_passivity.load()),
                  static_cast<unsigned long long>(counters.refused_owner.load()));
    events.push(sim::EventKind::kCommandRejected, sim::Severity::kWarning,
                cycle.output().sim_time_s, static_cast<double>(r), msg);
    last_rejected = r;
    last_reject_event_ns = t_ns;
  }

  void drain_events() {
    sim::SimEvent ev;
    while (events.pop(ev)) {
      if (ev.kind == sim::EventKind::kFault) ++faults;
      // the cycle clamps the newest command's K_ps: that command's master is who it is about
      if (ev.tags.subject == sim::EventSubject::kPositionGain) ev.tags.session = command_session;
      publish_event(ev);
    }
  }

  /// Readers of SlaveState at any rate (1 kHz and the observers' copies) less the masters (the
  /// command writers); warns once each time the count rises past options.max_observers.
  int count_observers(int command_writers) {
    const int readers = std::max(0, state_writer.matched_cached()) +
                        std::max(0, state_views.matched(0)) + std::max(0, state_views.matched(1));
    const int n = std::max(0, readers - std::max(0, command_writers));
    observers_max_seen = std::max(observers_max_seen, n);
    if (n > options.max_observers && !over_observer_limit) {
      char msg[128];
      std::snprintf(msg, sizeof(msg),
                    "%d observers read the state, above --max-observers %d: the loop's p99 may "
                    "grow",
                    n, options.max_observers);
      events.push(sim::EventKind::kInfo, sim::Severity::kWarning, cycle.output().sim_time_s,
                  static_cast<double>(n), msg);
    }
    over_observer_limit = n > options.max_observers;
    return n;
  }

  void maybe_publish_stats(std::int64_t t_ns, const RateLoop& loop) {
    if (t_ns - last_stats_ns < static_cast<std::int64_t>(options.stats_period_s * 1e9)) return;
    const double window_s = seconds_between(last_stats_ns, t_ns);
    ServerStats st;
    st.time_ns(now_ns());
    st.sim_time_s(cycle.output().sim_time_s);
    st.steps(cycle.steps());
    st.loop_rate_hz(window_s > 0 ? static_cast<double>(cycle.steps() - last_stats_steps) / window_s
                                 : 0.0);
    step_us.snapshot_into(scratch);  // capacity reserved: no allocation
    const Summary s = summarize_in_place(scratch);
    st.step_us_p50(s.p50);
    st.step_us_p99(s.p99);
    st.step_us_max(s.max);
    step_us.clear();
    st.overruns(loop.overruns());
    st.commands_received(counters.received.load());
    st.commands_rejected_nan(counters.rejected_nan.load());
    st.commands_rejected_workspace(counters.rejected_workspace.load());
    st.commands_rejected_stale(counters.rejected_stale.load());
    st.watchdog_trips(cycle.watchdog_trips());
    st.faults(faults);
    st.matched_state_readers(state_writer.matched_cached());  // never waits on the writer
    st.matched_command_writers(command_reader->matched());
    st.commands_rejected_passivity(counters.rejected_passivity.load());
    st.commands_refused_owner(counters.refused_owner.load());
    st.owner_session(owner.active ? owner.session : 0);
    st.ownership_changes(ownership_changes);
    st.commands_malformed(command_reader->malformed());
    st.samples_oversized(dds::oversized_samples());
    st.observers(count_observers(st.matched_command_writers()));
    st.max_observers(options.max_observers);
    stats_publisher.offer(st, /*wake=*/true);  // written by the publisher's thread
    last_stats_ns = t_ns;
    last_stats_steps = cycle.steps();
  }

  int run() {
    install_stop_signal_handlers();
    publish_scene();
    MeshPublisher meshes(model, cycle.data(), frame_writer, &frame_monitor_writer,
                         dds::topics::kMonitorRateHz);
    const auto visual_every = std::max<std::uint64_t>(
        1, static_cast<std::uint64_t>(std::llround(options.rate_hz / model.visual_rate_hz)));
    const std::int64_t t_start = now_ns();
    last_stats_ns = t_start;
    if (wants_thread_setup(options.realtime)) {
      const std::string problem = make_thread_realtime(options.realtime);
      if (!problem.empty()) {
        std::cerr << "teleop_server: warning: the physics loop stays a normal thread: " << problem
                  << "\n";
      }
    }
    const DmaLatencyHold dma(options.realtime.dma_latency_us);
    if (!dma.problem().empty()) {
      std::cerr << "teleop_server: warning: the cores may sleep deeply: " << dma.problem() << "\n";
    }
    RateLoop loop(options.rate_hz, 65536,
                  static_cast<std::int64_t>(options.realtime.spin_us) * 1000);
    const std::int64_t prewarm_ns = static_cast<std::int64_t>(options.realtime.prewarm_us) * 1000;
    SlaveState state;
    ReceivedCommand rc;
    std::uint64_t seen = 0;
    while (!stop_requested()) {
      const std::int64_t t0 = now_ns();
      if (options.duration_s > 0 && seconds_between(t_start, t0) >= options.duration_s) break;
      if (mailbox.take_if_newer(rc, seen)) {
        cycle.on_command(from_idl(rc.cmd), rc.receive_ns, rc.cmd.send_time_ns());
        command_session = rc.cmd.master_session();
      }
      take_owner(t0);
      cycle.step(t0, events);
      step_us.record(cycle.step_time_us());
      step_us_all.record(cycle.step_time_us());
      const sim::StepCost& cost = cycle.data().cost;
      collision_us.record(cost.collision_us);
      deformable_us.record(cost.deformable_us);
      slave_us.record(cost.slave_us);
      const std::int64_t tp = now_ns();
      pack_slave_state(cycle, counters.received.load(), owner, now_ns(), state);
      state_writer.write(state);
      state_views.offer(state);  // a copy under a try-lock; the views are written elsewhere
      if (cycle.steps() % visual_every == 0) meshes.offer(cycle.data(), cycle.output().sim_time_s);
      publish_us.record(static_cast<double>(now_ns() - tp) * 1e-3);
      report_rejections(t0);
      drain_events();
      maybe_publish_stats(t0, loop);
      if (prewarm_ns > 0) {
        loop.sleep_until_lead(prewarm_ns);
        keep(cycle.prewarm());
      }
      loop.wait();
    }
    command_reader->stop();
    state_writer.flush(0.5);  // what the loop handed over goes out before the summary
    event_publisher.flush(0.5);
    finish(loop, seconds_between(t_start, now_ns()));
    return 0;
  }

  void finish(const RateLoop& loop, double elapsed_s) {
    const Summary s = summarize(step_us_all.snapshot());
    if (!options.quiet) print_summary(loop, elapsed_s, s);
    // a summary that cannot be written is an error naming the file (exit status 1)
    if (!options.summary_json.empty()) write_summary(loop, elapsed_s, s);
  }

  void print_summary(const RateLoop& loop, double elapsed_s, const Summary& s) {
    const Summary c = summarize(collision_us.snapshot()), d = summarize(deformable_us.snapshot()),
                  sl = summarize(slave_us.snapshot()), pu = summarize(publish_us.snapshot());
    std::fprintf(stderr,
                 "teleop_server: step parts p50/p99 [us]: collision %.1f/%.1f, deformable "
                 "%.1f/%.1f, slave %.1f/%.1f, publish %.1f/%.1f\n",
                 c.p50, c.p99, d.p50, d.p99, sl.p50, sl.p99, pu.p50, pu.p99);
    std::fprintf(stderr,
                 "teleop_server: %llu steps in %.1f s, step p50 %.1f us p99 %.1f us, "
                 "%llu overruns, commands %llu received / %llu rejected (%llu not the owner's), "
                 "%llu owners, %llu watchdog trips, %llu K_ps clamped (allowed 0-%.6g N/m)\n",
                 static_cast<unsigned long long>(cycle.steps()), elapsed_s, s.p50, s.p99,
                 static_cast<unsigned long long>(loop.overruns()),
                 static_cast<unsigned long long>(counters.received.load()),
                 static_cast<unsigned long long>(rejected()),
                 static_cast<unsigned long long>(counters.refused_owner.load()),
                 static_cast<unsigned long long>(ownership_changes),
                 static_cast<unsigned long long>(cycle.watchdog_trips()),
                 static_cast<unsigned long long>(cycle.gains_clamped()), cycle.max_gain_n_per_m());
  }

  static OrderedJson percentiles(const Summary& p, bool with_max = true) {
    OrderedJson o = {{"p50", json_number(p.p50)}, {"p99", json_number(p.p99)}};
    if (with_max) o["max"] = json_number(p.max);
    return o;
  }

  void write_summary(const RateLoop& loop, double elapsed_s, const Summary& s) {
    const Summary late = summarize(loop.lateness_us().snapshot());
    OrderedJson f;
    f["version"] = version_string();
    f["scene"] = model.name;
    f["profile"] = options.dds.profile;
    f["insecure"] = options.dds.insecure;
    f["elapsed_s"] = json_number(elapsed_s);
    f["steps"] = cycle.steps();
    f["rate_hz"] = json_number(options.rate_hz);
    f["overruns"] = loop.overruns();
    f["step_us"] = percentiles(s);
    f["step_parts_us"] = {{"collision", percentiles(summarize(collision_us.snapshot()))},
                          {"deformable", percentiles(summarize(deformable_us.snapshot()))},
                          {"slave", percentiles(summarize(slave_us.snapshot()))},
                          {"publish", percentiles(summarize(publish_us.snapshot()))}};
    f["realtime_priority"] = options.realtime.priority;
    f["spin_us"] = options.realtime.spin_us;
    f["prewarm_us"] = options.realtime.prewarm_us;
    f["lock_memory"] = options.realtime.lock_memory;
    f["nice"] = options.realtime.nice;
    f["dma_latency_us"] = options.realtime.dma_latency_us;
    f["loop_jitter_us"] = percentiles(late, false);
    f["commands_received"] = counters.received.load();
    f["commands_accepted"] = counters.accepted.load();
    f["commands_rejected_nan"] = counters.rejected_nan.load();
    f["commands_rejected_workspace"] = counters.rejected_workspace.load();
    f["commands_rejected_stale"] = counters.rejected_stale.load();
    f["commands_rejected_passivity"] = counters.rejected_passivity.load();
    f["commands_refused_owner"] = counters.refused_owner.load();
    f["ownership_changes"] = ownership_changes;
    f["commands_malformed"] = command_reader->malformed();
    f["samples_oversized"] = dds::oversized_samples();
    f["observers_max"] = observers_max_seen;
    f["max_observers"] = options.max_observers;
    f["watchdog_trips"] = cycle.watchdog_trips();
    f["commands_gain_clamped"] = cycle.gains_clamped();
    f["max_position_gain_n_per_m"] = json_number(cycle.max_gain_n_per_m());
    f["network_threads"] = {
        {"states_dropped", state_writer.dropped()},
        {"events_dropped", event_publisher.dropped()},
        {"write_failures", state_writer.failures() + event_publisher.failures()}};
    f["faults"] = faults;
    write_text_file(options.summary_json, json_document(f));
  }
};

ServerNode::ServerNode(const ServerOptions& options, const sim::WorldModel& model)
    : impl_(std::make_unique<Impl>(options, model)) {}
ServerNode::~ServerNode() = default;
int ServerNode::run() { return impl_->run(); }

}  // namespace teleop::server
