#pragma once
// The network flags shared by every executable (header-only: the apps link CLI11).
//
//   --profile NAME             participant profile (deploy/profiles/*.xml, by profile_name)
//   --peer ADDR[:PORT]         unicast peer (lan, lan_unicast: UDP; wan_tcp_*: the TCP server,
//                              port default 5100); repeatable
//   --listen PORT              TCP listening port (wan_tcp_server default 5100)
//   --public-address ADDR      the address peers reach a TCP listener at (NAT / WAN address)
//   --discovery-server ADDR[:PORT]  discovery server of id 0, 1, ... in the order given
//                              (discovery_client; port default 11811); repeatable
//   --security-dir DIR         DDS Security files (secure profiles; deploy/make_security.sh)
//   --identity NAME            whose certificate, key and permissions in DIR (default: the
//                              executable's role: server, master or observer)
//   --insecure                 accept a profile that reaches beyond 127.0.0.1 without DDS
//                              Security (refused without it)
//
// Environment, used when the flag is absent: TELEOP_PEERS, TELEOP_LISTEN_PORT,
// TELEOP_PUBLIC_ADDRESS, TELEOP_DISCOVERY_SERVERS (lists separated by commas),
// TELEOP_SECURITY_DIR, TELEOP_IDENTITY, TELEOP_INSECURE=1.
#include <CLI/CLI.hpp>

#include "common/config/flags.hpp"
#include "common/dds/participant.hpp"

namespace teleop::dds {

/// --insecure: accept a profile that reaches beyond 127.0.0.1 without DDS Security.
inline void add_insecure_flag(CLI::App& app, NetworkFlags& f) {
  app.add_flag("--insecure", f.insecure,
               "accept a profile that reaches beyond 127.0.0.1 without DDS Security (lan, "
               "lan_unicast, wan_tcp_*, discovery_client): any host could command the slave "
               "(default: $TELEOP_INSECURE=1)");
}

/// Adds the flags to `app`; `role` is the default --identity of the secure profiles;
/// `listen_flag` names the TCP listening port's flag (teleop_bridge, whose --listen is its
/// WebSocket address, calls it --dds-listen).
inline void add_network_flags(CLI::App& app, NetworkFlags& f, const std::string& role = "observer",
                              const std::string& listen_flag = "--listen") {
  f.default_identity = role;
  app.add_option("--peer", f.peers,
                 "unicast peer ADDR[:PORT], repeatable (lan/lan_unicast: UDP; wan_tcp_client: "
                 "the server, port default 5100) (default: $TELEOP_PEERS)")
      ->type_name("ADDR[:PORT]")
      ->allow_extra_args(false);
  app.add_option(listen_flag, f.listen,
                 "TCP listening port of the wan_tcp profiles (default: $TELEOP_LISTEN_PORT, "
                 "wan_tcp_server 5100)")
      ->type_name("PORT");
  app.add_option("--public-address", f.public_address,
                 "address other hosts reach this TCP listener at (default: "
                 "$TELEOP_PUBLIC_ADDRESS)")
      ->type_name("ADDR");
  app.add_option("--discovery-server", f.discovery_servers,
                 "discovery server ADDR[:PORT] of id 0, 1, ... in order, repeatable (profile "
                 "discovery_client; port default 11811) (default: $TELEOP_DISCOVERY_SERVERS)")
      ->type_name("ADDR[:PORT]")
      ->allow_extra_args(false);
  app.add_option("--security-dir", f.security_dir,
                 "DDS Security files of the secure profiles, made by deploy/make_security.sh "
                 "(default: $TELEOP_SECURITY_DIR)")
      ->type_name("DIR");
  add_insecure_flag(app, f);
  app.add_option("--identity", f.identity,
                 "identity in --security-dir whose certificate, key and permissions to use "
                 "(default: $TELEOP_IDENTITY, else " +
                     role + ")")
      ->type_name("NAME");
}

/// --reconnect S of the clients (teleop_master, teleop_monitor): on a TCP client profile, with no
/// answer from a server for S seconds, make a new participant (Fast DDS 2.9's TCP client was seen
/// never to complete a connection, docs/networking.md). 0 = never; otherwise S is in
/// [kMinReconnectS, 3600].
constexpr double kMinReconnectS = 0.5;
inline void add_reconnect_flag(CLI::App& app, double& reconnect_s) {
  // a value the text check let through (a number in [0, 3600]) that is neither 0 nor enough
  const CLI::Validator never_or_enough(
      [](std::string& v) {
        const double s = std::stod(v);
        return s != 0.0 && s < kMinReconnectS
                   ? "'" + v + "' is out of the allowed range " +
                         config::range_text(kMinReconnectS, 3600.0) + " (0 = never)"
                   : std::string();
      },
      "");
  config::add_number(app, "--reconnect", reconnect_s, 0.0, 3600.0,
                     "TCP client profiles: with no answer from a server for this long, make a new "
                     "participant (a new connection) (0 = never; else at least " +
                         config::param_number_text(kMinReconnectS) + ")",
                     "s")
      ->check(never_or_enough)
      ->capture_default_str();
}

}  // namespace teleop::dds
