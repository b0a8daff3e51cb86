// teleop_master: the master-side client: a haptic device (simulated by default), a bilateral
// controller (position-position, force-position, wave-variables or tdpa), an injected delay
// channel in both directions, metrics, a safety layer, over DDS.
//
//   teleop_master [--scheme position-position|force-position|wave-variables|tdpa]
//                 [--wave-impedance B --wave-unmatched] [--tdpa-base position-position|...]
//                 [--script press-slip]
//                 [--delay 50ms --jitter 5ms --jitter-dist uniform|normal --reorder
//                  --loss 1% --burst-loss P_GB,P_BG --delay-spike AT,DUR,EXTRA
//                  --loss-window AT,DUR,P --seed N --channel-capacity N] [--config master.yaml]
//                 [--duration S] [--samples N] [--domain D] [--profile P]
//                 [--log FILE.csv] [--summary-json FILE]
//
// Exit status (docs/exit_codes.md): 0 session stable, 1 runtime failure, 2 bad command line,
// config or output path, 3 no server, 4 refused the slave, 5 degraded (the link), 6 oscillating,
// 7 out of spec, 8 unstable or cut.
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <cmath>
#include <iostream>
#include <optional>
#include <sstream>
#include <thread>

#include "client/control/controller_flags.hpp"
#include "client/device/device_factory.hpp"
#include "client/device/replay_device.hpp"
#include "client/net/delay_flags.hpp"
#include "client/node/master_node.hpp"
#include "common/config/config.hpp"
#include "common/config/flags.hpp"
#include "common/config/realtime_flags.hpp"
#include "common/dds/network_flags.hpp"
#include "common/dds/participant.hpp"
#include "common/util/files.hpp"
#include "common/util/progress.hpp"

namespace {

/// Every scene's command workspace lies within this box (the scene loader's range of
/// command.workspace_min_m / workspace_max_m) [m]: a contact point outside can never be reached.
constexpr double kContactPointLimitM = 100.0;

Eigen::Vector3d parse_point(const std::string& flag, const std::string& text) {
  const std::vector<double> lo(3, -kContactPointLimitM), hi(3, kContactPointLimitM);
  const std::vector<double> v = teleop::config::parse_numbers(flag, text, 3, lo, hi);
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

/// Command-line values that are applied on top of the YAML config (unset: keep it).
struct Flags {
  std::optional<int> domain;
  std::optional<std::string> profile;
  std::string config_file;
  std::optional<std::string> contact_point;
  teleop::master::DelayFlags delay;  ///< --delay, --jitter, ...: the channel's parameter table
  std::optional<double> link_timeout;
  std::optional<std::string> driver_timeout;
  teleop::master::ControllerFlags controller;  ///< --scheme, --kps, ...: the parameter table's
  teleop::dds::NetworkFlags net_flags;
  bool progress = false, no_progress = false;
  bool print_parameters = false;
  bool print_delay_parameters = false;
};

/// The session's length and rate, the DDS flags and the controller's flags.
void add_session_flags(CLI::App& app, teleop::master::MasterOptions& o, Flags& f) {
  using teleop::config::add_integer;
  using teleop::config::add_number;
  add_number(app, "--duration", o.duration_s, 0.0, 1e6,
             "session length after homing (0 = the script's length + 1 s)", "s");
  add_integer(app, "--samples", o.samples, 0.0, 1e12, "stop after N haptic cycles (0 = no limit)");
  add_number(app, "--rate", o.rate_hz, 10.0, 20000.0, "haptic loop rate", "Hz")
      ->capture_default_str();
  add_integer(app, "--domain", f.domain, 0.0, 232.0,
              "DDS domain id (default: $TELEOP_DOMAIN or 0)");
  app.add_option("--profile", f.profile,
                 "Fast DDS profile name in deploy/profiles or XML path (default: loopback)");
  teleop::dds::add_network_flags(app, f.net_flags, "master");
  app.add_option("--config", f.config_file,
                 "YAML with `controller:`, `delay:` (both directions) mappings; flags win");
  // the controller's parameters with a flag (client/control/controller_params.hpp)
  teleop::master::add_controller_flags(app, f.controller);
  app.add_flag("--print-parameters", f.print_parameters,
               "print the controller's parameter table (markdown) and exit")
      ->group("");
  app.add_flag("--print-delay-parameters", f.print_delay_parameters,
               "print the injected channel's parameter table (markdown) and exit")
      ->group("");
}

/// The device, the operator's script and the contact point.
void add_device_flags(CLI::App& app, teleop::master::MasterOptions& o, Flags& f) {
  using teleop::config::add_number;
  app.add_option("--device", o.device,
                 "haptic device: simulated | replay | external | evdev:/dev/input/eventN | "
                 "vendor[:NAME]")
      ->check(CLI::Validator(
          [](std::string& v) {
            if (v == "simulated" || v == "replay" || v == "external" ||
                teleop::master::is_hardware_device_name(v)) {
              return std::string();
            }
            return "--device '" + v +
                   "' is not one of simulated, replay, external, "
                   "evdev:/dev/input/eventN, vendor[:NAME]";
          },
          "DEVICE"))
      ->capture_default_str();
  app.add_option("--replay", o.replay_file, "CSV trajectory for --device replay");
  app.add_option("--script", o.script, "operator script of the simulated device")
      ->check(CLI::IsMember({"hold", "line", "circle", "step", "press-slip"}))
      ->capture_default_str();
  add_number(app, "--press-depth", o.press_depth_m, 0.0, 0.2, "press-slip depth below the surface",
             "m")
      ->capture_default_str();
  add_number(app, "--tremor", o.tremor_m, 0.0, 0.01, "operator tremor amplitude", "m");
  app.add_option("--contact-point", f.contact_point,
                 "slave point 'x,y,z' of the master origin (default: top of the first deformable "
                 "body, else the floor under the tip) [m], each in " +
                     teleop::config::help_range_text(-kContactPointLimitM, kContactPointLimitM))
      ->check(teleop::config::non_empty());
}

/// Declares every flag of teleop_master.
void add_flags(CLI::App& app, teleop::master::MasterOptions& o, Flags& f) {
  using teleop::config::add_number;
  add_session_flags(app, o, f);
  add_device_flags(app, o, f);
  teleop::master::add_delay_flags(app, f.delay, "both directions");
  add_number(app, "--homing", o.homing_s, 0.0, 60.0, "time to bring the slave to the script start",
             "s")
      ->capture_default_str();
  add_number(app, "--wait-server", o.wait_server_s, 0.0, 3600.0, "wait for the server this long",
             "s")
      ->capture_default_str();
  app.add_flag("--accept-tuning", o.accept_tuning,
               "apply live tuning requests (teleop/tuning: gains and injected delays, checked "
               "against the scheme and the device, ramped in; e.g. from teleop_viewer's tuning "
               "panel). Off: the master only publishes its tuning status");
  add_number(app, "--wait-owner", o.wait_owner_s, 0.0, 86400.0,
             "when another master owns the slave, wait this long for it to release it (or to "
             "fall silent) instead of exiting with status 4 (default 0)",
             "s");
  add_number(app, "--command-rate", o.command_rate_hz, 0.0, 20000.0,
             "commands to the slave per second, 1 to --rate (default and 0: one per haptic "
             "cycle; model-mediated: 1000 with the haptic loop at 4000)",
             "Hz");
  teleop::dds::add_reconnect_flag(app, o.reconnect_s);
  teleop::config::add_realtime_flags(app, o.realtime, "haptic loop", "cycle", false);
  app.add_option("--name", o.name,
                 "who this master is in the server's ownership events, up to 48 characters "
                 "(default IDENTITY@HOST:PID)");
  add_number(app, "--link-timeout", f.link_timeout, 0.001, 10.0,
             "no SlaveState for this long fades the force to zero", "s");
  app.add_option("--driver-timeout", f.driver_timeout,
                 "no valid device reading for this long (a driver process such as teleop_viewer "
                 "--drive that quit or hangs) holds the slave and fades the force to zero, with "
                 "its unit, 1ms-10s (default 100ms)");
  app.add_option("--log", o.log_csv, "per-cycle CSV log");
  app.add_option("--summary-json", o.summary_json, "JSON summary at exit");
  app.add_flag("--quiet", o.quiet, "print only warnings and errors");
  app.add_flag("--progress", f.progress,
               "the session's time line on stderr even when it is not a terminal");
  app.add_flag("--no-progress", f.no_progress, "no session time line");
}

/// Validates the flags and folds the YAML config (if any) and the flags into `o`.
/// @throws teleop::config::ConfigError naming the flag or file, the value and the range.
/// --config FILE: the controller and the injected delays from YAML (flags then go on top).
void apply_config_file(const Flags& f, teleop::master::MasterOptions& o) {
  if (f.config_file.empty()) return;
  const auto root = teleop::config::Node::load_file(f.config_file);
  root.reject_unknown_keys({"controller", "delay", "forward_delay", "backward_delay"});
  if (root.has("controller")) {
    o.controller = teleop::master::controller_params_from_yaml(root.at("controller"));
  }
  if (root.has("delay")) {
    o.forward = teleop::master::delay_config_from_yaml(root.at("delay"));
    o.backward = o.forward;
    o.backward.seed = o.forward.seed + 1;
  }
  if (root.has("forward_delay")) {
    o.forward = teleop::master::delay_config_from_yaml(root.at("forward_delay"));
  }
  if (root.has("backward_delay")) {
    o.backward = teleop::master::delay_config_from_yaml(root.at("backward_delay"));
  }
}

/// The DDS options, the CPU to pin to, the master's name and the output files.
void apply_session_flags(const Flags& f, teleop::master::MasterOptions& o) {
  o.dds =
      teleop::dds::resolve_participant_options(f.profile, f.domain, "teleop_master", f.net_flags);
  o.dds.announce_to_whole_domain = true;  // observers with any participant id find it
  teleop::dds::profile_file(o.dds.profile);
  // below the core count
  teleop::config::check_flag("--cpu", o.realtime.cpu, -1.0,
                             static_cast<double>(std::thread::hardware_concurrency()) - 1.0);
  if (o.name.size() > 48) {
    throw teleop::config::ConfigError("command line: --name '" + o.name + "' has " +
                                      std::to_string(o.name.size()) +
                                      " characters; at most 48 are allowed");
  }
  if (o.name.empty()) {
    char host[64] = {};
    gethostname(host, sizeof(host) - 1);
    const std::string who = o.dds.network.security.identity.empty()
                                ? std::string("master")
                                : o.dds.network.security.identity;
    o.name =
        who.substr(0, 16) + "@" + std::string(host).substr(0, 20) + ":" + std::to_string(getpid());
  }
  if (!o.log_csv.empty()) teleop::prepare_output_file("--log", o.log_csv);
  if (!o.summary_json.empty()) teleop::prepare_output_file("--summary-json", o.summary_json);
}

/// The injected channel's flags over both directions (after --config; backward's seed + 1).
void apply_channel_flags(const Flags& f, teleop::master::MasterOptions& o) {
  if (!f.delay.any()) return;
  teleop::master::apply_delay_flags(f.delay, o.forward);
  teleop::master::apply_delay_flags(f.delay, o.backward);
  o.backward.seed = o.forward.seed + 1;
}

/// --link-timeout and --driver-timeout (the latter with its unit).
void apply_timeout_flags(const Flags& f, teleop::master::MasterOptions& o) {
  if (f.link_timeout) o.safety.link_timeout_s = *f.link_timeout;
  if (f.driver_timeout) {
    const std::string& t = *f.driver_timeout;
    if (!t.empty() && t.find_last_of("0123456789.") + 1 == t.size()) {
      throw teleop::config::ConfigError("command line: --driver-timeout '" + t +
                                        "' has no unit; write it with one of s, ms, us, ns (e.g. " +
                                        t + "ms)");
    }
    o.driver_timeout_s = teleop::config::parse_duration_s("--driver-timeout", t);
    if (!(o.driver_timeout_s >= 0.001 && o.driver_timeout_s <= 10.0)) {
      throw teleop::config::ConfigError("command line: --driver-timeout '" + t +
                                        "' is out of the allowed range [1ms, 10s]");
    }
  }
}

void apply_flags(const CLI::App& app, const Flags& f, teleop::master::MasterOptions& o) {
  using teleop::config::check_flag;
  apply_session_flags(f, o);
  if (o.device == "replay" && o.replay_file.empty()) {
    throw teleop::config::ConfigError("command line: --device replay needs --replay FILE.csv");
  }
  // the trajectory is checked now, before any wait for a server (it is read again at the start)
  if (o.device == "replay") teleop::master::load_replay_csv(o.replay_file);
  apply_config_file(f, o);  // YAML first, flags on top
  teleop::master::apply_controller_flags(f.controller, o.controller);
  apply_channel_flags(f, o);
  if (f.contact_point) {
    o.contact_point_m = parse_point("--contact-point", *f.contact_point);
    o.has_contact_point = true;
  }
  apply_timeout_flags(f, o);
  // the scheme's own loop and command rates (SchemeTraits), unless told otherwise
  const teleop::master::SchemeTraits traits = teleop::master::scheme_traits(o.controller);
  if (traits.default_rate_hz > 0.0 && !app.count("--rate")) o.rate_hz = traits.default_rate_hz;
  if (traits.default_command_rate_hz > 0.0 && !app.count("--command-rate")) {
    o.command_rate_hz = std::min(traits.default_command_rate_hz, o.rate_hz);
  }
  // at most the haptic loop's rate (--rate, or model-mediated's 4000)
  if (o.command_rate_hz != 0.0) check_flag("--command-rate", o.command_rate_hz, 1.0, o.rate_hz);
  // below the haptic loop's period (1 / --rate)
  check_flag("--spin-us", o.realtime.spin_us, 0.0, std::ceil(1e6 / o.rate_hz) - 1.0);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"teleop_master: master-side client of the teleoperation system"};
  teleop::master::MasterOptions o;
  Flags f;
  add_flags(app, o, f);
  if (const int status = teleop::config::parse_command_line(app, "teleop_master", argc, argv);
      status >= 0) {
    return status;
  }
  if (f.print_parameters) {
    std::cout << teleop::master::controller_params_markdown();
    return 0;
  }
  if (f.print_delay_parameters) {
    std::cout << teleop::master::delay_params_markdown();
    return 0;
  }
  try {
    apply_flags(app, f, o);
    teleop::set_progress_mode(teleop::progress_mode_from(f.progress, f.no_progress, o.quiet));
    teleop::master::MasterNode node(o);
    return node.run();
  } catch (const teleop::config::ConfigError& e) {
    std::cerr << "teleop_master: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "teleop_master: error: " << e.what() << "\n";
    return 1;
  }
}
