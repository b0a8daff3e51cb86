// teleop_bridge: serves a session's teleop/* topics over the Foxglove WebSocket protocol, so
// Foxglove, Lichtblick or any foxglove.websocket.v1 client can watch it.
//
//   teleop_bridge [--domain D] [--profile P] [--listen 127.0.0.1:8765 | --port 8765]
//                 [--tls-cert PEM --tls-key PEM] [--token-file FILE] [--insecure-listen]
//                 [--full-rate] [--queue-kb 4096] [--max-clients 32] [--duration S]
//                 [--stats-s 10] [--quiet]
//
// It joins the DDS domain like an observer (subscribes only; by default to the rate-limited
// copies of the 1 kHz topics, --full-rate adds the 1 kHz topics themselves), listens on
// 127.0.0.1 unless --listen names another address, advertises each topic as a channel with
// encoding cdr and its IDL as an omgidl schema, and forwards each sample's serialized CDR
// payload unchanged. It also publishes JSON channels for 3-D panels (bridge/scene:
// foxglove.SceneUpdate, bridge/transforms: foxglove.FrameTransforms) and for its own page
// (bridge/plot, bridge/events), and serves that page to a browser at http(s)://ADDR:PORT/.
// Latched topics (scene, mesh topology, tuning status, events, bridge/scene) reach a late
// subscriber at once. A non-loopback --listen needs TLS (--tls-cert, --tls-key) and an access
// token (--token-file: clients send it as ?token=... or "Authorization: Bearer ..."; a request
// without it gets 401, counted) unless --insecure-listen says otherwise. Each client has
// a send queue bounded by --queue-kb: a slow client loses mesh frames first, each drop counted,
// reported to it in a status message, on the periodic stderr line and in the exit summary.
// Clients can only subscribe and unsubscribe; anything else is answered with a status message.
//
// Exit status: 0 done, 2 bad command line, 1 runtime failure (DDS, the port in use).
#include <CLI/CLI.hpp>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>
#include <thread>

#include "client/bridge/bridge.hpp"
#include "common/config/config.hpp"
#include "common/config/flags.hpp"
#include "common/dds/network_flags.hpp"
#include "common/util/clock.hpp"
#include "common/util/signals.hpp"

namespace {

using namespace teleop;

/// Address and port of --listen ("ADDR:PORT", "[V6]:PORT"). @throws config::ConfigError.
void parse_listen(const std::string& text, bridge::BridgeOptions& bo) {
  const auto colon = text.rfind(':');
  const auto bad = [&](const std::string& why) {
    return config::ConfigError("--listen '" + text + "': " + why +
                               " (expected ADDR:PORT, e.g. 0.0.0.0:8765, PORT 0-65535)");
  };
  if (colon == std::string::npos || colon == 0) throw bad("no ':PORT'");
  std::string addr = text.substr(0, colon);
  if (addr.size() > 2 && addr.front() == '[' && addr.back() == ']') {
    addr = addr.substr(1, addr.size() - 2);
  }
  const std::string port = text.substr(colon + 1);
  if (port.empty() || port.size() > 5 ||
      port.find_first_not_of("0123456789") != std::string::npos || std::stoi(port) > 65535) {
    throw bad("port '" + port + "' is not a number in 0-65535");
  }
  bo.address = addr;
  bo.port = std::stoi(port);
}

bool is_loopback(const std::string& addr) {
  return addr.rfind("127.", 0) == 0 || addr == "::1" || addr == "localhost";
}

/// The access token of --token-file: its first line, 16-4096 printable characters.
std::string read_token(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw config::ConfigError("--token-file '" + path + "': cannot read it");
  std::string token;
  std::getline(f, token);
  while (!token.empty() && std::isspace(static_cast<unsigned char>(token.back()))) token.pop_back();
  bool printable = true;
  for (const char c : token) printable = printable && c > 0x20 && c < 0x7f && c != '&' && c != '#';
  if (token.size() < 16 || token.size() > 4096 || !printable) {
    throw config::ConfigError("--token-file '" + path + "': the token (first line) has " +
                              std::to_string(token.size()) +
                              " characters; allowed: 16-4096 printable ASCII characters, no "
                              "spaces, '&' or '#' (e.g. openssl rand -hex 24 > FILE)");
  }
  return token;
}

/// Checks the access flags together: a non-loopback address needs TLS and a token.
void check_access(bridge::BridgeOptions& bo, const std::string& token_file, bool insecure) {
  auto& a = bo.access;
  if (a.tls_cert_file.empty() != a.tls_key_file.empty()) {
    throw config::ConfigError("--tls-cert and --tls-key go together (the certificate and its key)");
  }
  if (!token_file.empty()) a.token = read_token(token_file);
  if (is_loopback(bo.address)) return;
  if ((a.tls_cert_file.empty() || a.token.empty()) && !insecure) {
    throw config::ConfigError(
        "--listen " + bo.address +
        " is not a loopback address: remote viewers need --tls-cert, --tls-key and --token-file "
        "(or --insecure-listen to serve anyone on the network without them)");
  }
  if (insecure && (a.tls_cert_file.empty() || a.token.empty())) {
    std::fprintf(stderr,
                 "teleop_bridge: WARNING: --insecure-listen: serving %s without %s: anyone who "
                 "can reach this address can watch the session\n",
                 bo.address.c_str(),
                 a.tls_cert_file.empty() && a.token.empty() ? "TLS or an access token"
                 : a.tls_cert_file.empty()                  ? "TLS"
                                                            : "an access token");
  }
}

/// The line on stdout once the bridge listens: the channels, the addresses and the page.
void print_serving(bridge::Bridge& b, const bridge::BridgeOptions& bo,
                   const teleop::dds::ParticipantOptions& opts) {
  const bool tls = !bo.access.tls_cert_file.empty();
  const std::string host =
      bo.address.find(':') != std::string::npos ? "[" + bo.address + "]" : bo.address;
  std::printf(
      "teleop_bridge: serving %zu channels of domain %d (profile %s) on "
      "%s://%s:%d (foxglove.websocket.v1), the page at %s://%s:%d/%s; read-only\n",
      b.topics().size(), opts.domain, opts.profile.c_str(), tls ? "wss" : "ws", host.c_str(),
      b.port(), tls ? "https" : "http", host.c_str(), b.port(),
      bo.access.token.empty() ? "" : "?token=(the token)");
  std::fflush(stdout);
}

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
  bool quiet = false, insecure = false;
  std::string listen, token_file;
  config::add_integer(app, "--domain", domain, 0.0, 232.0,
                      "DDS domain id (default: $TELEOP_DOMAIN or 0)");
  app.add_option("--profile", profile,
                 "Fast DDS profile name in deploy/profiles or XML path (default: loopback)");
  teleop::dds::NetworkFlags net_flags;
  teleop::dds::add_network_flags(app, net_flags, "observer", "--dds-listen");
  auto* port_opt = config::add_integer(app, "--port", bo.port, 0.0, 65535.0,
                                       "TCP port on 127.0.0.1 (0: the system picks one and it is "
                                       "printed)")
                       ->capture_default_str();
  app.add_option("--listen", listen,
                 "ADDR:PORT to listen on (default 127.0.0.1:8765); a non-loopback address needs "
                 "--tls-cert, --tls-key and --token-file")
      ->excludes(port_opt);
  app.add_option("--tls-cert", bo.access.tls_cert_file, "TLS certificate (chain), PEM")
      ->check(config::non_empty());
  app.add_option("--tls-key", bo.access.tls_key_file, "TLS private key of --tls-cert, PEM")
      ->check(config::non_empty());
  app.add_option("--token-file", token_file,
                 "file whose first line is the access token every client must send")
      ->check(config::non_empty());
  app.add_flag("--insecure-listen", insecure,
               "allow a non-loopback --listen without TLS or a token (anyone may watch)");
  app.add_flag("--full-rate", bo.full_rate,
               "also serve the 1 kHz topics (master_command, slave_state, master_state, "
               "device_*); by default their rate-limited _view/_monitor copies");
  config::add_number(app, "--queue-kb", queue_kb, 64.0, 1048576.0, "per-client send queue bound",
                     "KiB")
      ->capture_default_str();
  config::add_integer(app, "--max-clients", bo.max_clients, 1.0, 1024.0, "clients served at once")
      ->capture_default_str();
  config::add_number(app, "--duration", duration_s, 0.0, 1e6,
                     "stop after this long (0 = until SIGINT)", "s");
  config::add_number(app, "--stats-s", stats_s, 0.0, 3600.0,
                     "print the counts to stderr this often (0 = off)", "s")
      ->capture_default_str();
  app.add_flag("--quiet", quiet, "print only warnings, errors and the periodic counts");
  if (const int status = config::parse_command_line(app, "teleop_bridge", argc, argv);
      status >= 0) {
    return status == 2 ? 2 : status;
  }
  try {
    bo.queue_bytes = static_cast<std::size_t>(queue_kb * 1024.0);
    if (!listen.empty()) parse_listen(listen, bo);
    check_access(bo, token_file, insecure);
    const auto opts =
        teleop::dds::resolve_participant_options(profile, domain, "teleop_bridge", net_flags);
    teleop::dds::profile_file(opts.profile);
    install_stop_signal_handlers();
    teleop::dds::Participant p(opts);
    std::unique_ptr<bridge::Bridge> b;
    try {
      b = std::make_unique<bridge::Bridge>(p, bo);
    } catch (const std::invalid_argument& e) {
      std::cerr << "teleop_bridge: --tls-cert/--tls-key: " << e.what() << "\n";
      return 2;
    }
    if (!quiet) print_serving(*b, bo, opts);
    return serve(*b, duration_s, stats_s, quiet);
  } catch (const config::ConfigError& e) {
    std::cerr << "teleop_bridge: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "teleop_bridge: error: " << e.what() << "\n";
    return 1;
  }
}
