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

/// The loop flags whose range depends on the machine or the rate (the others were checked on
/// their text). @throws teleop::config::ConfigError naming the flag, the value and the range.
void check_loop_flags(const teleop::RealtimeOptions& realtime, double rate_hz) {
  using teleop::config::check_flag;
  // below the core count
  check_flag("--cpu", realtime.cpu, -1.0,
             static_cast<double>(std::thread::hardware_concurrency()) - 1);
  // below the physics step's period (1 / the rate)
  check_flag("--spin-us", realtime.spin_us, 0.0, std::ceil(1e6 / rate_hz) - 1.0);
  check_flag("--prewarm-us", realtime.prewarm_us, 0.0, std::ceil(1e6 / rate_hz) - 1.0);
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
  using teleop::config::add_integer;
  using teleop::config::add_number;
  // the scene's fields these flags override, with their ranges (server/world/scene_params.cpp)
  const auto& rate = teleop::sim::scene_param(teleop::sim::physics_params(), "rate_hz");
  const auto& timeout = teleop::sim::scene_param(teleop::sim::command_params(), "timeout_s");
  add_number(app, "--rate", f.rate_hz, rate.lo, rate.hi,
             "physics rate (default: the scene's physics.rate_hz)", rate.unit);
  add_number(app, "--command-timeout", f.command_timeout_s, timeout.lo, timeout.hi,
             "hold the slave when no valid command arrives for this long (default: the scene's "
             "command.timeout_s, 0.05)",
             timeout.unit);
  add_number(app, "--owner-timeout", f.owner_timeout_s, 0.001, 60.0,
             "a master owning the slave loses it when none of its commands arrived for this "
             "long, and another may take it over; at least the command timeout (default: 0.5, "
             "or the command timeout if longer)",
             "s");
  add_number(app, "--duration", f.duration_s, 0.0, 1e7,
             "stop after this many seconds (0 = run until SIGINT)", "s");
  add_number(app, "--stats-period", f.stats_period_s, 0.1, 10.0, "ServerStats period", "s");
  add_integer(app, "--max-observers", f.max_observers, 0.0, 10000.0,
              "warn (an event) when more observers than this read the state")
      ->capture_default_str();
  add_integer(app, "--domain", f.domain, 0.0, 232.0,
              "DDS domain id (default: $TELEOP_DOMAIN or 0)");
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

/// The server's options from the flags and the scene; the values whose range depends on the
/// scene, another flag or the machine are checked here (the others were checked on their text).
/// @throws teleop::config::ConfigError naming the flag, the value and the range.
teleop::server::ServerOptions server_options(const Flags& f, const teleop::sim::WorldModel& scene) {
  teleop::server::ServerOptions o;
  o.dds =
      teleop::dds::resolve_participant_options(f.profile, f.domain, "teleop_server", f.net_flags);
  o.dds.announce_to_whole_domain = true;     // observers with any participant id find it
  teleop::dds::profile_file(o.dds.profile);  // fail early with the list of profiles
  // the rate defaults from the scene (the flag and the scene's field have one range)
  o.rate_hz = f.rate_hz.value_or(scene.physics_rate_hz);
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
  // the command timeout defaults from the scene (one range, as the rate's)
  o.command_timeout_s = f.command_timeout_s.value_or(scene.command_timeout_s);
  // at least the command timeout
  o.owner_timeout_s = teleop::config::check_flag(
      "--owner-timeout", f.owner_timeout_s.value_or(std::max(0.5, o.command_timeout_s)),
      o.command_timeout_s, 60.0);
  o.duration_s = f.duration_s;
  o.stats_period_s = f.stats_period_s;
  o.max_observers = f.max_observers;
  o.summary_json = f.summary_json;
  if (!f.summary_json.empty()) teleop::prepare_output_file("--summary-json", f.summary_json);
  check_loop_flags(f.realtime, o.rate_hz);
  o.realtime = f.realtime;
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
