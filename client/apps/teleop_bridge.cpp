// teleop_bridge: serves a session's teleop/* topics over the Foxglove WebSocket protocol, so
// Foxglove, Lichtblick or any foxglove.websocket.v1 client can watch it.
//
//   teleop_bridge [--domain D] [--profile P] [--port 8765] [--full-rate] [--queue-kb 4096]
//                 [--max-clients 32] [--duration S] [--stats-s 10] [--quiet]
//
// It joins the DDS domain like an observer (subscribes only; by default to the rate-limited
// copies of the 1 kHz topics, --full-rate adds the 1 kHz topics themselves), listens on
// 127.0.0.1 only, advertises each topic as a channel with encoding cdr and its IDL as an
// omgidl schema, and forwards each sample's serialized CDR payload unchanged. Latched topics
// (scene, mesh topology, tuning status, events) reach a late subscriber at once. Each client has
// a send queue bounded by --queue-kb: a slow client loses mesh frames first, each drop counted,
// reported to it in a status message, on the periodic stderr line and in the exit summary.
// Clients can only subscribe and unsubscribe; anything else is answered with a status message.
//
// Exit status: 0 done, 2 bad command line, 1 runtime failure (DDS, the port in use).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <optional>
#include <thread>

#include "client/bridge/bridge.hpp"
#include "common/config/config.hpp"
#include "common/config/flags.hpp"
#include "common/dds/network_flags.hpp"
#include "common/util/clock.hpp"
#include "common/util/signals.hpp"

namespace {

using namespace teleop;

/// Serves until SIGINT/SIGTERM or --duration; prints the counts every --stats-s.
int serve(bridge::Bridge& b, double duration_s, double stats_s, bool quiet) {
  const auto t0 = now_ns();
  auto last = t0;
  while (!stop_requested()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    const auto now = now_ns();
    if (duration_s > 0.0 && seconds_between(t0, now) >= duration_s) break;
    if (stats_s > 0.0 && seconds_between(last, now) >= stats_s) {
      last = now;
      std::fprintf(stderr, "teleop_bridge: %s\n", bridge::counts_line(b.counts()).c_str());
    }
  }
  b.stop();
  if (!quiet) {
    std::fprintf(stderr, "teleop_bridge: done: %s\n", bridge::counts_line(b.counts()).c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"teleop_bridge: serve a session over the Foxglove WebSocket protocol"};
  std::optional<int> domain;
  std::optional<std::string> profile;
  bridge::BridgeOptions bo;
  double duration_s = 0.0, stats_s = 10.0, queue_kb = 4096.0;
  bool quiet = false;
  app.add_option("--domain", domain, "DDS domain id, 0-232 (default: $TELEOP_DOMAIN or 0)")
      ->check(config::integer_in(0.0, 232.0));
  app.add_option("--profile", profile,
                 "Fast DDS profile name in deploy/profiles or XML path (default: loopback)");
  teleop::dds::NetworkFlags net_flags;
  teleop::dds::add_network_flags(app, net_flags, "observer");
  app.add_option("--port", bo.port,
                 "TCP port on 127.0.0.1, 0-65535 (0: the system picks one and it is printed)")
      ->check(config::integer_in(0.0, 65535.0))
      ->capture_default_str();
  app.add_flag("--full-rate", bo.full_rate,
               "also serve the 1 kHz topics (master_command, slave_state, master_state, "
               "device_*); by default their rate-limited _view/_monitor copies");
  app.add_option("--queue-kb", queue_kb, "per-client send queue bound [KiB], 64-1048576")
      ->check(config::number_in(64.0, 1048576.0))
      ->capture_default_str();
  app.add_option("--max-clients", bo.max_clients, "clients served at once, 1-1024")
      ->check(config::integer_in(1.0, 1024.0))
      ->capture_default_str();
  app.add_option("--duration", duration_s, "stop after this long [s], 0-1e6; 0 = until SIGINT")
      ->check(config::number_in(0.0, 1e6));
  app.add_option("--stats-s", stats_s, "print the counts to stderr this often [s], 0-3600; 0 = off")
      ->check(config::number_in(0.0, 3600.0))
      ->capture_default_str();
  app.add_flag("--quiet", quiet, "print only warnings, errors and the periodic counts");
  if (const int status = config::parse_command_line(app, "teleop_bridge", argc, argv);
      status >= 0) {
    return status == 2 ? 2 : status;
  }
  try {
    config::check_flag("--duration", duration_s, 0.0, 1e6);
    config::check_flag("--stats-s", stats_s, 0.0, 3600.0);
    config::check_flag("--queue-kb", queue_kb, 64.0, 1048576.0);
    bo.queue_bytes = static_cast<std::size_t>(queue_kb * 1024.0);
    const auto opts =
        teleop::dds::resolve_participant_options(profile, domain, "teleop_bridge", net_flags);
    teleop::dds::profile_file(opts.profile);
    install_stop_signal_handlers();
    teleop::dds::Participant p(opts);
    bridge::Bridge b(p, bo);
    if (!quiet) {
      std::printf(
          "teleop_bridge: serving %zu topics of domain %d (profile %s) on "
          "ws://127.0.0.1:%d (foxglove.websocket.v1)\n",
          b.topics().size(), opts.domain, opts.profile.c_str(), b.port());
      std::fflush(stdout);
    }
    return serve(b, duration_s, stats_s, quiet);
  } catch (const config::ConfigError& e) {
    std::cerr << "teleop_bridge: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "teleop_bridge: error: " << e.what() << "\n";
    return 1;
  }
}
