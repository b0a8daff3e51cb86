// teleop_server: owns the virtual world and publishes it over DDS.
//
//   teleop_server [--scene deploy/scenes/default.yaml] [--rate 1000] [--command-timeout 0.05]
//                 [--duration S] [--domain D] [--profile loopback] [--summary-json FILE]
//
// Exit status: 0 clean stop (SIGINT/SIGTERM or --duration), 2 bad command line or scene,
// 1 runtime failure (e.g. DDS could not start).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <iostream>
#include <optional>
#include <sstream>
#include <thread>

#include "common/config/config.hpp"
#include "common/config/flags.hpp"
#include "common/config/realtime_flags.hpp"
#include "common/dds/network_flags.hpp"
#include "common/dds/participant.hpp"
#include "common/util/data_dir.hpp"
#include "common/util/files.hpp"
#include "server/node/server_node.hpp"
#include "server/world/scene_params.hpp"
#include "server/world/world_model.hpp"

namespace {

/// The loop flags checked against their ranges (the spin and the prewarm below the period).
teleop::RealtimeOptions checked_loop_flags(const teleop::RealtimeOptions& realtime,
                                           double rate_hz) {
  using teleop::config::check_flag;
  teleop::RealtimeOptions o;
  o.priority = static_cast<int>(check_flag("--realtime", realtime.priority, 0.0, 99.0));
  o.cpu = static_cast<int>(check_flag(
      "--cpu", realtime.cpu, -1.0, static_cast<double>(std::thread::hardware_concurrency()) - 1));
  o.spin_us = static_cast<int>(
      check_flag("--spin-us", realtime.spin_us, 0.0, std::ceil(1e6 / rate_hz) - 1.0));
  o.prewarm_us = static_cast<int>(
      check_flag("--prewarm-us", realtime.prewarm_us, 0.0, std::ceil(1e6 / rate_hz) - 1.0));
  o.lock_memory = realtime.lock_memory;
  o.nice = static_cast<int>(check_flag("--nice", realtime.nice, -20.0, 19.0));
  o.dma_latency_us =
      static_cast<int>(check_flag("--dma-latency-us", realtime.dma_latency_us, -1.0, 1e5));
  return o;
}

/// teleop_server's command line.
struct Flags {
  std::string scene_file = teleop::data_path("scenes/default.yaml");
  std::optional<double> rate_hz;
  std::optional<double> command_timeout_s;
  std::optional<double> owner_timeout_s;
  double duration_s = 0.0;
  double stats_period_s = 1.0;
  int max_observers = 32;
  std::optional<int> domain;
  std::optional<std::string> profile;
  std::string summary_json;
  bool quiet = false;
  bool print_scene_parameters = false;
  teleop::RealtimeOptions realtime;
  teleop::dds::NetworkFlags net_flags;
};

/// Declares every flag of teleop_server.
void add_flags(CLI::App& app, Flags& f) {
  app.add_option("--scene", f.scene_file, "scene YAML file")->capture_default_str();
  app.add_option("--rate", f.rate_hz, "physics rate [Hz], 10-20000 (default: the scene's)")
      ->check(teleop::config::number_in(10.0, 20000.0));
  app.add_option("--command-timeout", f.command_timeout_s,
                 "hold the slave when no valid command arrives for this long [s], 0.001-10 "
                 "(default: the scene's, 0.05)")
      ->check(teleop::config::number_in(0.001, 10.0));
  app.add_option("--owner-timeout", f.owner_timeout_s,
                 "a master owning the slave loses it when none of its commands arrived for "
                 "this long, and another may take it over [s], from the command timeout to 60 "
                 "(default: 0.5, or the command timeout if longer)")
      ->check(teleop::config::number_in(0.001, 60.0));
  app.add_option("--duration", f.duration_s,
                 "stop after this many seconds, 0-1e7; 0 = run until SIGINT")
      ->check(teleop::config::number_in(0.0, 1e7));
  app.add_option("--stats-period", f.stats_period_s, "ServerStats period [s], 0.1-10")
      ->check(teleop::config::number_in(0.1, 10.0));
  app.add_option("--max-observers", f.max_observers,
                 "warn (an event) when more observers than this read the state, 0-10000")
      ->check(teleop::config::integer_in(0.0, 10000.0))
      ->capture_default_str();
  app.add_option("--domain", f.domain, "DDS domain id, 0-232 (default: $TELEOP_DOMAIN or 0)")
      ->check(teleop::config::integer_in(0.0, 232.0));
  app.add_option("--profile", f.profile,
                 "Fast DDS profile name in deploy/profiles or XML path (default: loopback)");
  teleop::dds::add_network_flags(app, f.net_flags, "server");
  app.add_option("--summary-json", f.summary_json, "write a JSON summary here at exit");
  teleop::config::add_realtime_flags(app, f.realtime, "physics loop", "step", true);
  app.add_flag("--quiet", f.quiet, "print only warnings and errors");
  app.add_flag("--print-scene-parameters", f.print_scene_parameters,
               "print the table of the scene file's plain fields (markdown) and exit")
      ->group("");
}

/// The server's options from the flags and the scene, each checked against its range.
/// @throws teleop::config::ConfigError naming the flag, the value and the range.
teleop::server::ServerOptions server_options(const Flags& f, const teleop::sim::WorldModel& scene) {
  teleop::server::ServerOptions o;
  o.dds =
      teleop::dds::resolve_participant_options(f.profile, f.domain, "teleop_server", f.net_flags);
  o.dds.announce_to_whole_domain = true;     // observers with any participant id find it
  teleop::dds::profile_file(o.dds.profile);  // fail early with the list of profiles
  o.rate_hz = teleop::config::check_flag("--rate", f.rate_hz.value_or(scene.physics_rate_hz), 10.0,
                                         20000.0);
  if (f.rate_hz) {  // the scene's own rate was checked at load
    const std::string problem = teleop::sim::physics_rate_problem(scene, o.rate_hz);
    if (!problem.empty()) {
      std::ostringstream os;
      os << "command line: --rate " << o.rate_hz << " " << problem;
      throw teleop::config::ConfigError(os.str());
    }
  }
  if (!f.quiet) {
    for (const std::string& note : teleop::sim::physics_rate_notes(scene, o.rate_hz)) {
      std::cout << "teleop_server: " << f.scene_file << ": " << note << "\n";
    }
  }
  o.command_timeout_s = teleop::config::check_flag(
      "--command-timeout", f.command_timeout_s.value_or(scene.command_timeout_s), 0.001, 10.0);
  o.owner_timeout_s = teleop::config::check_flag(
      "--owner-timeout", f.owner_timeout_s.value_or(std::max(0.5, o.command_timeout_s)),
      o.command_timeout_s, 60.0);
  o.duration_s = teleop::config::check_flag("--duration", f.duration_s, 0.0, 1e7);
  o.stats_period_s = teleop::config::check_flag("--stats-period", f.stats_period_s, 0.1, 10.0);
  o.max_observers = static_cast<int>(
      teleop::config::check_flag("--max-observers", f.max_observers, 0.0, 10000.0));
  o.summary_json = f.summary_json;
  if (!f.summary_json.empty()) teleop::prepare_output_file("--summary-json", f.summary_json);
  o.realtime = checked_loop_flags(f.realtime, o.rate_hz);
  o.quiet = f.quiet;
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"teleop_server: simulation server of the teleoperation system"};
  Flags f;
  add_flags(app, f);
  if (const int status = teleop::config::parse_command_line(app, "teleop_server", argc, argv);
      status >= 0) {
    return status == 2 ? 2 : status;
  }
  if (f.print_scene_parameters) {
    std::cout << teleop::sim::scene_params_markdown();
    return 0;
  }
  try {
    const teleop::sim::WorldModel scene = teleop::sim::load_world_model(f.scene_file);
    teleop::server::ServerNode node(server_options(f, scene), scene);
    return node.run();
  } catch (const teleop::config::ConfigError& e) {
    std::cerr << "teleop_server: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "teleop_server: error: " << e.what() << "\n";
    return 1;
  }
}
