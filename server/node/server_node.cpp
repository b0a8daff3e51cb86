#include "server/node/server_node.hpp"

#include <condition_variable>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <mutex>
#include <thread>
#include <vector>

#include "common/dds/endpoint.hpp"
#include "common/util/clock.hpp"
#include "common/util/rate_loop.hpp"
#include "common/util/signals.hpp"
#include "common/util/stats.hpp"
#include "server/node/command_validation.hpp"
#include "server/node/scene_objects.hpp"
#include "server/world/scene_world.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace teleop::server {

namespace {

/// Newest accepted command and when it arrived (server clock).
struct ReceivedCommand {
  MasterCommand cmd;
  std::int64_t receive_ns = 0;
};

template <std::size_t N>
void copy3(std::array<double, N>& dst, const Eigen::Vector3d& v) {
  dst[0] = v.x();
  dst[1] = v.y();
  dst[2] = v.z();
}

std::string json_number(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.6g", v);
  return buf;
}

}  // namespace

struct ServerNode::Impl {
  ServerOptions options;
  sim::SceneConfig scene;
  std::unique_ptr<sim::World> world;
  dds::Participant participant;
  dds::Writer<SlaveStatePubSubType> state_writer;
  dds::Writer<SceneDescriptionPubSubType> scene_writer;
  dds::Writer<EventPubSubType> event_writer;
  dds::Writer<ServerStatsPubSubType> stats_writer;
  dds::Writer<MeshTopologyPubSubType> topology_writer;
  dds::Writer<MeshFramePubSubType> frame_writer;
  CommandCounters counters;
  dds::Mailbox<ReceivedCommand> mailbox;
  // reader-thread state
  eprosima::fastrtps::rtps::InstanceHandle_t current_writer;
  bool have_last = false;
  std::uint64_t last_seq = 0;
  PassivityHistory passivity_history;
  std::unique_ptr<dds::Reader<MasterCommandPubSubType>> command_reader;

  // loop state
  sim::EventQueue events;
  std::uint64_t event_seq = 0;
  std::uint64_t watchdog_trips = 0;
  std::uint64_t faults = 0;
  SampleWindow step_us{1 << 16};
  SampleWindow step_us_all{1 << 20};

  // mesh frame thread: the loop copies positions into `back` and flips; the publisher thread
  // converts and writes, so observers never slow the physics
  std::mutex mesh_mutex;
  std::condition_variable mesh_cv;
  std::vector<Eigen::Matrix3Xd> mesh_back;
  bool mesh_pending = false;
  bool mesh_stop = false;
  std::uint64_t mesh_frame_no = 0;
  double mesh_time_s = 0.0;
  std::thread mesh_thread;

  Impl(const ServerOptions& o, const sim::SceneConfig& s)
      : options(o),
        scene(s),
        world(sim::make_world(s)),
        participant(o.dds),
        state_writer(participant, dds::topics::kSlaveState, dds::TopicQos::kStream),
        scene_writer(participant, dds::topics::kScene, dds::TopicQos::kLatched),
        event_writer(participant, dds::topics::kEvents, dds::TopicQos::kEventLog),
        stats_writer(participant, dds::topics::kServerStats, dds::TopicQos::kReliableStream),
        topology_writer(participant, dds::topics::kMeshTopology, dds::TopicQos::kLatched),
        frame_writer(participant, dds::topics::kMeshFrame, dds::TopicQos::kStream) {
    command_reader = std::make_unique<dds::Reader<MasterCommandPubSubType>>(
        participant, dds::topics::kMasterCommand, dds::TopicQos::kStream,
        [this](const MasterCommand& c, const eprosima::fastdds::dds::SampleInfo& info) {
          on_command(c, info);
        });
  }

  ~Impl() {
    command_reader->stop();
    {
      std::lock_guard<std::mutex> lock(mesh_mutex);
      mesh_stop = true;
    }
    mesh_cv.notify_all();
    if (mesh_thread.joinable()) mesh_thread.join();
  }

  void on_command(const MasterCommand& c, const eprosima::fastdds::dds::SampleInfo& info) {
    counters.received.fetch_add(1);
    // a new master (another writer) restarts the sequence numbering
    if (!have_last || info.publication_handle != current_writer) {
      if (have_last) {
        // switching writers: accept the new one's numbering
        have_last = false;
      }
      passivity_history = PassivityHistory{};
      current_writer = info.publication_handle;
    }
    CommandVerdict v =
        validate_command(c, scene.workspace_min_m, scene.workspace_max_m, last_seq, have_last);
    if (v == CommandVerdict::kAccepted) v = validate_passivity(c, passivity_history);
    switch (v) {
      case CommandVerdict::kAccepted:
        break;
      case CommandVerdict::kOutsideWorkspace:
        counters.rejected_workspace.fetch_add(1);
        return;
      case CommandVerdict::kStale:
        counters.rejected_stale.fetch_add(1);
        return;
      case CommandVerdict::kBadPassivity:
        counters.rejected_passivity.fetch_add(1);
        return;
      default:
        counters.rejected_nan.fetch_add(1);
        return;
    }
    have_last = true;
    last_seq = c.seq();
    counters.accepted.fetch_add(1);
    mailbox.put(ReceivedCommand{c, now_ns()});
  }

  void publish_event(const sim::SimEvent& e) {
    Event ev;
    ev.seq(++event_seq);
    ev.time_ns(now_ns());
    ev.source("server");
    ev.kind(static_cast<std::uint8_t>(e.kind));
    ev.severity(static_cast<std::uint8_t>(e.severity));
    ev.message(e.message);
    ev.value(e.value);
    event_writer.write(ev);
    if (!options.quiet && e.severity != sim::Severity::kInfo) {
      std::cerr << "teleop_server: event: " << e.message << "\n";
    }
  }

  void publish_scene() {
    SceneDescription d;
    d.name(scene.name);
    copy3(d.gravity_mps2(), scene.gravity_mps2);
    d.physics_rate_hz(options.rate_hz);
    d.visual_rate_hz(scene.visual_rate_hz);
    d.tip_radius_m(scene.tool.radius_m);
    d.joint_count(static_cast<std::uint32_t>(world->output().joint_count));
    copy3(d.workspace_min_m(), scene.workspace_min_m);
    copy3(d.workspace_max_m(), scene.workspace_max_m);
    for (const auto& p : scene.planes) {
      SceneObject o;
      o.id(p.id);
      o.name(p.name);
      o.kind(OBJECT_PLANE);
      copy3(o.normal(), p.normal);
      o.offset_m(p.offset_m);
      o.stiffness_n_per_m(p.stiffness_n_per_m);
      d.objects().push_back(o);
    }
    SceneObject tool;
    tool.id(1);
    tool.name(scene.kind == "tool" ? "tool" : "tip");
    tool.kind(OBJECT_TOOL);
    tool.size_m()[0] = scene.tool.radius_m;
    tool.mass_kg(scene.tool.mass_kg);
    d.objects().push_back(tool);
    for (int i = 0; i < world->deformable_count(); ++i) {
      const auto view = world->deformable(i);
      SceneObject o;
      o.id(view.object_id);
      o.name("deformable" + std::to_string(i));
      o.kind(OBJECT_DEFORMABLE_MESH);
      // bounding sphere at rest: centroid and largest node distance
      const Eigen::Vector3d centre = view.positions->rowwise().mean();
      const double radius = (view.positions->colwise() - centre).colwise().norm().maxCoeff();
      copy3(o.position_m(), centre);
      o.size_m()[0] = radius;
      d.objects().push_back(o);
      MeshTopology t;
      t.object_id(view.object_id);
      t.vertex_count(static_cast<std::uint32_t>(view.positions->cols()));
      auto& idx = t.triangle_indices();
      idx.reserve(static_cast<std::size_t>(view.triangles->size()));
      for (Eigen::Index c = 0; c < view.triangles->cols(); ++c) {
        for (int r = 0; r < 3; ++r)
          idx.push_back(static_cast<std::uint32_t>((*view.triangles)(r, c)));
      }
      topology_writer.write(t);
    }
    // the robot's frames at q = 0, so observers can draw the arm from the joint positions
    if (const auto* sw = dynamic_cast<const sim::SceneWorld*>(world.get());
        sw != nullptr && sw->has_robot()) {
      append_robot_frames(sw->robot()->model(), d);
    }
    scene_writer.write(d);
  }

  void start_mesh_thread() {
    const int n = world->deformable_count();
    if (n == 0) return;
    mesh_back.resize(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i)
      mesh_back[static_cast<std::size_t>(i)] = *world->deformable(i).positions;
    mesh_thread = std::thread([this, n] {
      std::vector<Eigen::Matrix3Xd> front(static_cast<std::size_t>(n));
      MeshFrame frame;
      while (true) {
        std::uint64_t no = 0;
        double t = 0.0;
        {
          std::unique_lock<std::mutex> lock(mesh_mutex);
          mesh_cv.wait(lock, [this] { return mesh_pending || mesh_stop; });
          if (mesh_stop) return;
          std::swap(front, mesh_back);
          mesh_pending = false;
          no = mesh_frame_no;
          t = mesh_time_s;
        }
        for (int i = 0; i < n; ++i) {
          const auto& x = front[static_cast<std::size_t>(i)];
          frame.object_id(world->deformable(i).object_id);
          frame.frame(no);
          frame.sim_time_s(t);
          auto& pos = frame.positions_m();
          pos.resize(static_cast<std::size_t>(x.size()));
          for (Eigen::Index k = 0; k < x.size(); ++k)
            pos[static_cast<std::size_t>(k)] = static_cast<float>(x.data()[k]);
          frame_writer.write(frame);
        }
      }
    });
  }

  /// Called from the loop at the visual rate: copies positions into the back buffer.
  void offer_mesh_frame(double sim_time_s) {
    if (!mesh_thread.joinable()) return;
    std::unique_lock<std::mutex> lock(mesh_mutex, std::try_to_lock);
    if (!lock.owns_lock()) return;  // publisher busy swapping: skip this frame, never block
    for (int i = 0; i < world->deformable_count(); ++i) {
      mesh_back[static_cast<std::size_t>(i)] =
          *world->deformable(i).positions;  // same size: no allocation
    }
    ++mesh_frame_no;
    mesh_time_s = sim_time_s;
    mesh_pending = true;
    lock.unlock();
    mesh_cv.notify_one();
  }

  void publish_stats(std::uint64_t steps, const RateLoop& loop, double window_s,
                     std::uint64_t window_steps, std::vector<double>& scratch) {
    ServerStats st;
    st.time_ns(now_ns());
    st.sim_time_s(world->output().sim_time_s);
    st.steps(steps);
    st.loop_rate_hz(window_s > 0 ? static_cast<double>(window_steps) / window_s : 0.0);
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
    st.watchdog_trips(watchdog_trips);
    st.faults(faults);
    st.matched_state_readers(state_writer.matched());
    st.matched_command_writers(command_reader->matched());
    st.commands_rejected_passivity(counters.rejected_passivity.load());
    stats_writer.write(st);
  }

  int run() {
    install_stop_signal_handlers();
    publish_scene();
    start_mesh_thread();
    sim::SimEvent start{};
    std::snprintf(start.message, sizeof(start.message),
                  "server started: scene '%s', %.0f Hz, domain %d, profile %s", scene.name.c_str(),
                  options.rate_hz, options.dds.domain, options.dds.profile.c_str());
    publish_event(start);
    if (!options.quiet) std::cerr << "teleop_server: " << start.message << "\n";

    const double dt = 1.0 / options.rate_hz;
    const auto timeout_ns = static_cast<std::int64_t>(options.command_timeout_s * 1e9);
    const std::int64_t t_start = now_ns();
    const auto visual_every = std::max<std::uint64_t>(
        1, static_cast<std::uint64_t>(std::llround(options.rate_hz / scene.visual_rate_hz)));
    RateLoop loop(options.rate_hz);
    SlaveState state;
    ReceivedCommand rc;
    std::uint64_t seen = 0;
    bool have_command = false;
    bool holding = true;
    sim::WorldCommand wc;
    wc.position_m = scene.tool_start_m;
    wc.hold = true;
    // the slave side of the passivity schemes (the same code as the in-process slaves)
    passivity::SlavePassivityPort port;
    passivity::SlavePortCommand port_cmd;
    std::uint64_t steps = 0;
    std::int64_t last_stats_ns = t_start;
    std::uint64_t last_stats_steps = 0;
    std::vector<double> scratch;
    scratch.reserve(step_us.capacity());
    std::uint64_t last_rejected = 0;
    std::int64_t last_reject_event_ns = 0;
    sim::SimEvent ev;

    while (!stop_requested()) {
      const std::int64_t t0 = now_ns();
      if (options.duration_s > 0 && seconds_between(t_start, t0) >= options.duration_s) break;

      // newest valid command
      if (mailbox.take_if_newer(rc, seen)) {
        wc = to_world_command(rc.cmd);
        port_cmd = to_port_command(rc.cmd);
        state.command_seq(rc.cmd.seq());
        state.command_send_time_ns(rc.cmd.send_time_ns());
        have_command = true;
      }
      // watchdog: hold the slave when commands stop arriving
      const bool stale = !have_command || (t0 - rc.receive_ns) > timeout_ns;
      if (stale != holding) {
        holding = stale;
        if (have_command) {
          if (holding) {
            ++watchdog_trips;
            events.push(sim::EventKind::kWatchdog, sim::Severity::kWarning,
                        world->output().sim_time_s, seconds_between(rc.receive_ns, t0) * 1e3,
                        "no valid command within the timeout: holding the slave");
          } else {
            events.push(sim::EventKind::kWatchdog, sim::Severity::kInfo, world->output().sim_time_s,
                        0.0, "commands resumed: tracking again");
          }
        }
      }
      sim::WorldCommand applied = wc;
      applied.hold = wc.hold || holding;

      // wave variables / TDPA: the port turns the command into the tool's target, using the
      // state and contact force of the last step
      const bool port_active = passivity::SlavePassivityPort::handles(port_cmd.scheme);
      if (port_active) {
        const sim::WorldOutput& before = world->output();
        passivity::SlavePortCommand pc = port_cmd;
        pc.enabled = !applied.hold;
        passivity::SlavePortState ps;
        ps.position_m = before.tip_position_m;
        ps.velocity_mps = before.tip_velocity_mps;
        ps.contact_force_n = before.contact_force_n;
        const passivity::TrackingGains gains{applied.kp_override_n_per_m > 0.0
                                                 ? applied.kp_override_n_per_m
                                                 : before.tracking_kp_n_per_m,
                                             before.tracking_kd_ns_per_m};
        const passivity::SlavePortTarget t = port.before_step(pc, ps, gains, dt);
        applied.position_m = t.position_m;
        applied.velocity_mps = t.velocity_mps;
        applied.hold = t.hold;
      } else if (port.scheme() != 0xff) {
        port.reset();  // left the passivity scheme: the next session starts afresh
      }

      const std::int64_t ts = now_ns();
      world->step(applied, dt, events);
      const double step_time_us = static_cast<double>(now_ns() - ts) * 1e-3;
      if (port_active) port.after_step(world->output().tracking_force_n, dt);
      step_us.record(step_time_us);
      step_us_all.record(step_time_us);
      ++steps;

      // publish the slave state, echoing the newest command
      const sim::WorldOutput& out = world->output();
      state.seq(steps);
      state.server_time_ns(now_ns());
      state.sim_time_s(out.sim_time_s);
      const auto nj = static_cast<std::size_t>(out.joint_count);
      state.joint_position_rad().resize(nj);
      state.joint_velocity_radps().resize(nj);
      state.joint_torque_nm().resize(nj);
      for (std::size_t j = 0; j < nj; ++j) {
        state.joint_position_rad()[j] = out.q_rad[j];
        state.joint_velocity_radps()[j] = out.qd_radps[j];
        state.joint_torque_nm()[j] = out.tau_nm[j];
      }
      copy3(state.tip_position_m(), out.tip_position_m);
      state.tip_orientation_wxyz() = {out.tip_orientation.w(), out.tip_orientation.x(),
                                      out.tip_orientation.y(), out.tip_orientation.z()};
      copy3(state.tip_linear_velocity_mps(), out.tip_velocity_mps);
      copy3(state.tip_angular_velocity_radps(), out.tip_angular_velocity_radps);
      copy3(state.contact_force_n(), out.contact_force_n);
      copy3(state.contact_torque_nm(), out.contact_torque_nm);
      state.penetration_m(out.penetration_m);
      state.deformation_m(out.deformation_m);
      state.in_contact(out.in_contact);
      state.contact_object(out.contact_object);
      state.holding(applied.hold);
      state.step_time_us(static_cast<float>(step_time_us));
      state.commands_received(counters.received.load());
      {
        const passivity::SlavePortReport& pr = port.report();
        state.passivity_session(port_active ? pr.session : 0);
        copy3(state.wave_v(), pr.wave_v);
        copy3(state.wave_v_integral(), pr.wave_v_integral);
        copy3(state.wave_v_energy_j(), pr.wave_v_energy_j);
        state.tdpa_energy_in_j(pr.tdpa_energy_in_j);
        state.tdpa_energy_out_j(pr.tdpa_energy_out_j);
        state.passivity_dissipated_j(pr.dissipated_j);
      }
      state_writer.write(state);

      if (steps % visual_every == 0) offer_mesh_frame(out.sim_time_s);

      // rejected commands: one event per second at most, with the count
      const std::uint64_t rejected =
          counters.rejected_nan.load() + counters.rejected_workspace.load() +
          counters.rejected_stale.load() + counters.rejected_passivity.load();
      if (rejected != last_rejected && t0 - last_reject_event_ns > 1'000'000'000LL) {
        char msg[sizeof(sim::SimEvent::message)];
        std::snprintf(msg, sizeof(msg),
                      "rejected commands so far: %llu non-finite, %llu outside workspace, "
                      "%llu stale, %llu bad passivity",
                      static_cast<unsigned long long>(counters.rejected_nan.load()),
                      static_cast<unsigned long long>(counters.rejected_workspace.load()),
                      static_cast<unsigned long long>(counters.rejected_stale.load()),
                      static_cast<unsigned long long>(counters.rejected_passivity.load()));
        events.push(sim::EventKind::kCommandRejected, sim::Severity::kWarning, out.sim_time_s,
                    static_cast<double>(rejected), msg);
        last_rejected = rejected;
        last_reject_event_ns = t0;
      }
      while (events.pop(ev)) {
        if (ev.kind == sim::EventKind::kFault) ++faults;
        publish_event(ev);
      }
      if (t0 - last_stats_ns >= static_cast<std::int64_t>(options.stats_period_s * 1e9)) {
        publish_stats(steps, loop, seconds_between(last_stats_ns, t0), steps - last_stats_steps,
                      scratch);
        last_stats_ns = t0;
        last_stats_steps = steps;
      }
      loop.wait();
    }
    command_reader->stop();
    write_summary(steps, loop, seconds_between(t_start, now_ns()));
    if (!options.quiet) {
      const Summary s = summarize(step_us_all.snapshot());
      std::fprintf(stderr,
                   "teleop_server: %llu steps in %.1f s, step p50 %.1f us p99 %.1f us, "
                   "%llu overruns, commands %llu received / %llu rejected, %llu watchdog trips\n",
                   static_cast<unsigned long long>(steps), seconds_between(t_start, now_ns()),
                   s.p50, s.p99, static_cast<unsigned long long>(loop.overruns()),
                   static_cast<unsigned long long>(counters.received.load()),
                   static_cast<unsigned long long>(
                       counters.rejected_nan.load() + counters.rejected_workspace.load() +
                       counters.rejected_stale.load() + counters.rejected_passivity.load()),
                   static_cast<unsigned long long>(watchdog_trips));
    }
    return 0;
  }

  void write_summary(std::uint64_t steps, const RateLoop& loop, double elapsed_s) {
    if (options.summary_json.empty()) return;
    const Summary s = summarize(step_us_all.snapshot());
    const Summary late = summarize(loop.lateness_us().snapshot());
    std::ofstream f(options.summary_json);
    f << "{\n"
      << "  \"scene\": \"" << scene.name << "\",\n"
      << "  \"elapsed_s\": " << json_number(elapsed_s) << ",\n"
      << "  \"steps\": " << steps << ",\n"
      << "  \"rate_hz\": " << json_number(options.rate_hz) << ",\n"
      << "  \"overruns\": " << loop.overruns() << ",\n"
      << "  \"step_us\": {\"p50\": " << json_number(s.p50) << ", \"p99\": " << json_number(s.p99)
      << ", \"max\": " << json_number(s.max) << "},\n"
      << "  \"loop_jitter_us\": {\"p50\": " << json_number(late.p50)
      << ", \"p99\": " << json_number(late.p99) << "},\n"
      << "  \"commands_received\": " << counters.received.load() << ",\n"
      << "  \"commands_accepted\": " << counters.accepted.load() << ",\n"
      << "  \"commands_rejected_nan\": " << counters.rejected_nan.load() << ",\n"
      << "  \"commands_rejected_workspace\": " << counters.rejected_workspace.load() << ",\n"
      << "  \"commands_rejected_stale\": " << counters.rejected_stale.load() << ",\n"
      << "  \"commands_rejected_passivity\": " << counters.rejected_passivity.load() << ",\n"
      << "  \"watchdog_trips\": " << watchdog_trips << ",\n"
      << "  \"faults\": " << faults << "\n"
      << "}\n";
  }
};

ServerNode::ServerNode(const ServerOptions& options, const sim::SceneConfig& scene)
    : impl_(std::make_unique<Impl>(options, scene)) {}
ServerNode::~ServerNode() = default;
int ServerNode::run() { return impl_->run(); }

}  // namespace teleop::server
