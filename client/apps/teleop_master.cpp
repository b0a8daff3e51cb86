// teleop_master: the master-side client: haptic loop, bilateral control, round-trip
// measurement, over DDS.
//
//   teleop_master [--duration 10] [--samples N] [--rate 1000] [--domain D] [--profile P]
//                 [--log FILE.csv] [--summary-json FILE] [--motion circle|press|hold]
//
// Exit status: 0 session done, 2 bad command line, 3 no server found, 1 runtime failure.
#include <CLI/CLI.hpp>
#include <iostream>
#include <optional>

#include "client/node/master_node.hpp"
#include "common/config/config.hpp"
#include "common/dds/participant.hpp"

int main(int argc, char** argv) {
  CLI::App app{"teleop_master: master-side client of the teleoperation system"};
  teleop::master::MasterOptions o;
  std::optional<int> domain;
  std::optional<std::string> profile;
  app.add_option("--duration", o.duration_s, "session length [s], 0-1e6 (0 = no limit)")
      ->capture_default_str();
  app.add_option("--samples", o.samples, "stop after N commands (0 = no limit)");
  app.add_option("--rate", o.rate_hz, "haptic loop rate [Hz], 10-20000")->capture_default_str();
  app.add_option("--domain", domain, "DDS domain id, 0-232 (default: $TELEOP_DOMAIN or 0)");
  app.add_option("--profile", profile,
                 "Fast DDS profile name in deploy/profiles or XML path (default: loopback)");
  app.add_option("--log", o.log_csv, "per-cycle CSV log");
  app.add_option("--summary-json", o.summary_json, "JSON summary at exit");
  app.add_option("--motion", o.motion, "scripted device motion")
      ->check(CLI::IsMember({"circle", "press", "hold"}))
      ->capture_default_str();
  app.add_option("--wait-server", o.wait_server_s, "wait for the server this long [s]")
      ->capture_default_str();
  app.add_option("--link-timeout", o.link_timeout_s,
                 "no SlaveState for this long fades the force to zero [s], 0.001-10")
      ->capture_default_str();
  app.add_flag("--quiet", o.quiet, "print only warnings, errors and nothing else");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::cerr << "teleop_master: " << e.what() << "\n\n" << app.help();
    return 2;
  }
  try {
    using teleop::config::check_flag;
    o.dds = teleop::dds::resolve_participant_options(profile, domain, "teleop_master");
    teleop::dds::profile_file(o.dds.profile);
    check_flag("--duration", o.duration_s, 0.0, 1e6);
    check_flag("--rate", o.rate_hz, 10.0, 20000.0);
    check_flag("--wait-server", o.wait_server_s, 0.0, 3600.0);
    check_flag("--link-timeout", o.link_timeout_s, 0.001, 10.0);
    if (o.duration_s == 0 && o.samples == 0) {
      std::cerr << "teleop_master: note: no --duration or --samples: runs until SIGINT\n";
    }
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
