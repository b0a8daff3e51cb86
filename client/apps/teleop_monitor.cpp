// teleop_monitor: a terminal observer of a running session. Subscribes only (it never
// writes), so any number may join or leave without disturbing the loop.
//
//   teleop_monitor [--domain D] [--profile P] [--period 1] [--duration S]
//
// Every period it prints the rates of SlaveState and MasterState, the server's loop rate,
// step-time percentiles and overruns, the round trip reported by the master, the tip position,
// contact force and penetration; events are printed as they arrive.
#include <CLI/CLI.hpp>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <mutex>
#include <optional>
#include <thread>

#include "common/dds/network_flags.hpp"
#include "common/config/config.hpp"
#include "common/dds/endpoint.hpp"
#include "common/util/clock.hpp"
#include "common/util/signals.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace {

const char* event_kind(std::uint8_t k) {
  switch (k) {
    case teleop::EVENT_CONTACT_BEGIN:
      return "contact-begin";
    case teleop::EVENT_CONTACT_END:
      return "contact-end";
    case teleop::EVENT_WATCHDOG:
      return "watchdog";
    case teleop::EVENT_FAULT:
      return "FAULT";
    case teleop::EVENT_MODE_CHANGE:
      return "mode";
    case teleop::EVENT_COMMAND_REJECTED:
      return "rejected";
    case teleop::EVENT_LIMIT:
      return "limit";
    case teleop::EVENT_SAFETY:
      return "safety";
    default:
      return "info";
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"teleop_monitor: terminal observer of a teleoperation session"};
  std::optional<int> domain;
  std::optional<std::string> profile;
  double period_s = 1.0;
  double duration_s = 0.0;
  app.add_option("--domain", domain, "DDS domain id, 0-232 (default: $TELEOP_DOMAIN or 0)");
  app.add_option("--profile", profile, "Fast DDS profile (default: loopback)");
  teleop::dds::NetworkFlags net_flags;
  teleop::dds::add_network_flags(app, net_flags);
  app.add_option("--period", period_s, "print period [s], 0.1-60")->capture_default_str();
  app.add_option("--duration", duration_s, "stop after this long [s]; 0 = until SIGINT");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "teleop_monitor: " << e.what() << "\n\n" << app.help();
    return 2;
  }
  try {
    using namespace teleop;
    config::check_flag("--period", period_s, 0.1, 60.0);
    config::check_flag("--duration", duration_s, 0.0, 1e7);
    const auto opts = teleop::dds::resolve_participant_options(profile, domain, "teleop_monitor", net_flags);
    teleop::dds::Participant p(opts);
    install_stop_signal_handlers();

    std::mutex m;
    SlaveState slave;
    MasterState master;
    ServerStats stats;
    std::string scene_name;
    bool have_stats = false, have_slave = false, have_master = false;
    std::atomic<std::uint64_t> n_slave{0}, n_master{0}, n_frames{0};

    teleop::dds::Reader<SlaveStatePubSubType> r_slave(
        p, teleop::dds::topics::kSlaveState, teleop::dds::TopicQos::kStream,
        [&](const SlaveState& s, const eprosima::fastdds::dds::SampleInfo&) {
          ++n_slave;
          std::lock_guard<std::mutex> l(m);
          slave = s;
          have_slave = true;
        });
    teleop::dds::Reader<MasterStatePubSubType> r_master(
        p, teleop::dds::topics::kMasterState, teleop::dds::TopicQos::kStream,
        [&](const MasterState& s, const eprosima::fastdds::dds::SampleInfo&) {
          ++n_master;
          std::lock_guard<std::mutex> l(m);
          master = s;
          have_master = true;
        });
    teleop::dds::Reader<ServerStatsPubSubType> r_stats(
        p, teleop::dds::topics::kServerStats, teleop::dds::TopicQos::kReliableStream,
        [&](const ServerStats& s, const eprosima::fastdds::dds::SampleInfo&) {
          std::lock_guard<std::mutex> l(m);
          stats = s;
          have_stats = true;
        });
    teleop::dds::Reader<SceneDescriptionPubSubType> r_scene(
        p, teleop::dds::topics::kScene, teleop::dds::TopicQos::kLatched,
        [&](const SceneDescription& s, const eprosima::fastdds::dds::SampleInfo&) {
          std::lock_guard<std::mutex> l(m);
          scene_name = s.name();
          std::printf("scene '%s': %zu objects, %u joints, physics %.0f Hz, tip radius %.3f m\n",
                      s.name().c_str(), s.objects().size(), s.joint_count(), s.physics_rate_hz(),
                      s.tip_radius_m());
          std::fflush(stdout);
        });
    teleop::dds::Reader<MeshFramePubSubType> r_frames(
        p, teleop::dds::topics::kMeshFrame, teleop::dds::TopicQos::kStream,
        [&](const MeshFrame&, const eprosima::fastdds::dds::SampleInfo&) { ++n_frames; });
    teleop::dds::Reader<EventPubSubType> r_events(
        p, teleop::dds::topics::kEvents, teleop::dds::TopicQos::kEventLog,
        [&](const Event& e, const eprosima::fastdds::dds::SampleInfo&) {
          std::printf("event %-7s %-13s %s (%.3g)\n", e.source().c_str(), event_kind(e.kind()),
                      e.message().c_str(), e.value());
          std::fflush(stdout);
        });

    const auto t0 = now_ns();
    auto last = t0;
    std::uint64_t last_slave = 0, last_master = 0, last_frames = 0;
    while (!stop_requested()) {
      std::this_thread::sleep_for(std::chrono::duration<double>(period_s));
      const auto now = now_ns();
      const double dt = seconds_between(last, now);
      last = now;
      const double slave_hz = static_cast<double>(n_slave - last_slave) / dt;
      const double master_hz = static_cast<double>(n_master - last_master) / dt;
      const double frame_hz = static_cast<double>(n_frames - last_frames) / dt;
      last_slave = n_slave;
      last_master = n_master;
      last_frames = n_frames;
      std::lock_guard<std::mutex> l(m);
      std::printf("t=%6.1fs  slave_state %6.0f Hz  master_state %5.0f Hz  mesh %4.0f Hz",
                  seconds_between(t0, now), slave_hz, master_hz, frame_hz);
      if (have_stats) {
        std::printf(
            "  | server %6.0f Hz step p50 %.1f us p99 %.1f us overruns %llu "
            "rejected %llu watchdog %llu",
            stats.loop_rate_hz(), stats.step_us_p50(), stats.step_us_p99(),
            static_cast<unsigned long long>(stats.overruns()),
            static_cast<unsigned long long>(stats.commands_rejected_nan() +
                                            stats.commands_rejected_workspace() +
                                            stats.commands_rejected_stale()),
            static_cast<unsigned long long>(stats.watchdog_trips()));
      }
      std::printf("\n");
      if (have_slave) {
        const auto& x = slave.tip_position_m();
        const auto& f = slave.contact_force_n();
        std::printf(
            "           tip (%.3f, %.3f, %.3f) m  contact %s  force (%.2f, %.2f, %.2f) N"
            "  penetration %.2f mm%s\n",
            x[0], x[1], x[2], slave.in_contact() ? "yes" : "no ", f[0], f[1], f[2],
            slave.penetration_m() * 1e3, slave.holding() ? "  HOLDING" : "");
      }
      if (have_master) {
        const auto& fm = master.rendered_force_n();
        std::printf(
            "           master rtt %.3f ms  rendered force (%.2f, %.2f, %.2f) N  "
            "error %.1f mm  link %s\n",
            master.rtt_ms(), fm[0], fm[1], fm[2], master.position_error_m() * 1e3,
            master.link_ok() ? "ok" : "LOST");
      }
      std::fflush(stdout);
      if (duration_s > 0 && seconds_between(t0, now) >= duration_s) break;
    }
    return 0;
  } catch (const teleop::config::ConfigError& e) {
    std::cerr << "teleop_monitor: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "teleop_monitor: error: " << e.what() << "\n";
    return 1;
  }
}
