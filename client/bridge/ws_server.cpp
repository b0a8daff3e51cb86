#include "client/bridge/ws_server.hpp"

#include <chrono>
#include <fstream>
#include <map>
#include <stdexcept>
#include <thread>
#include <vector>
#include <websocketpp/config/asio.hpp>
#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

namespace teleop::bridge {

using Hdl = websocketpp::connection_hdl;
namespace asio = websocketpp::lib::asio;

namespace {

std::string query_value(const std::string& resource, const std::string& key) {
  const auto q = resource.find('?');
  if (q == std::string::npos) return {};
  std::size_t at = q + 1;
  while (at < resource.size()) {
    auto end = resource.find('&', at);
    if (end == std::string::npos) end = resource.size();
    const std::string pair = resource.substr(at, end - at);
    const auto eq = pair.find('=');
    if (eq != std::string::npos && pair.substr(0, eq) == key) return pair.substr(eq + 1);
    at = end + 1;
  }
  return {};
}

bool same(const std::string& a, const std::string& b) {
  // constant time in the content (the length of the expected token is no secret)
  unsigned diff = a.size() == b.size() ? 0u : 1u;
  for (std::size_t i = 0; i < b.size(); ++i) {
    diff |= static_cast<unsigned>(static_cast<unsigned char>(i < a.size() ? a[i] : 0) ^
                                  static_cast<unsigned char>(b[i]));
  }
  return diff == 0;
}

bool readable(const std::string& path) {
  std::ifstream f(path);
  return f.good();
}

}  // namespace

bool token_matches(const std::string& token, const std::string& resource,
                   const std::string& header) {
  if (token.empty()) return true;
  const std::string bearer = "Bearer ";
  if (header.compare(0, bearer.size(), bearer) == 0 && same(header.substr(bearer.size()), token)) {
    return true;
  }
  return same(query_value(resource, "token"), token);
}

struct WsServer::Impl {
  virtual ~Impl() = default;
  virtual int port() const = 0;
  virtual void start() = 0;
  virtual void post(std::function<void()> fn) = 0;
  virtual bool send(ClientId id, const void* data, std::size_t size, bool text) = 0;
  virtual std::size_t buffered(ClientId id) const = 0;
  virtual void stop() = 0;
};

namespace {

template <class Config>
struct ServerImpl final : WsServer::Impl {
  using Server = websocketpp::server<Config>;
  Server server;
  WsHandlers handlers;
  WsAccess access;
  std::string subprotocol;
  int tick_ms = 20;
  int port_ = 0;
  std::unique_ptr<asio::steady_timer> timer;
  std::map<Hdl, ClientId, std::owner_less<Hdl>> ids;         // server thread only
  std::map<ClientId, typename Server::connection_ptr> cons;  // server thread only
  ClientId next_id = 1;
  std::thread thread;
  bool stopped = false;

  bool authorized(typename Server::connection_ptr con) {
    if (token_matches(access.token, con->get_resource(),
                      con->get_request_header("Authorization"))) {
      return true;
    }
    con->set_status(websocketpp::http::status_code::unauthorized);
    con->set_body(
        "teleop_bridge: an access token is required (?token=... or Authorization: "
        "Bearer ...)\n");
    if (handlers.unauthorized) handlers.unauthorized(con->get_remote_endpoint());
    return false;
  }
  bool validate(Hdl hdl) {
    auto con = server.get_con_from_hdl(hdl);
    if (!authorized(con)) return false;
    bool offered = false;
    for (const auto& p : con->get_requested_subprotocols()) offered = offered || p == subprotocol;
    if (!offered) {
      con->set_status(websocketpp::http::status_code::bad_request);
      return false;
    }
    if (!handlers.accept()) {
      con->set_status(websocketpp::http::status_code::service_unavailable);
      return false;
    }
    con->select_subprotocol(subprotocol);
    return true;
  }
  void http(Hdl hdl) {
    auto con = server.get_con_from_hdl(hdl);
    if (!authorized(con)) return;
    std::string path = con->get_resource();
    path = path.substr(0, path.find('?'));
    HttpReply r;
    if (con->get_request().get_method() == "GET" && handlers.http) r = handlers.http(path);
    con->set_status(static_cast<websocketpp::http::status_code::value>(r.status));
    con->replace_header("Content-Type", r.content_type);
    con->replace_header("Cache-Control", "no-store");
    con->set_body(r.body);
  }
  void arm() {
    timer->expires_after(std::chrono::milliseconds(tick_ms));
    timer->async_wait([this](const asio::error_code& ec) {
      if (ec) return;
      handlers.tick();
      arm();
    });
  }
  void install_handlers();
  void listen(const std::string& address, int port);

  int port() const override { return port_; }
  void start() override {
    arm();
    thread = std::thread([this] { server.run(); });
  }
  void post(std::function<void()> fn) override {
    asio::post(server.get_io_service(), std::move(fn));
  }
  bool send(ClientId id, const void* data, std::size_t size, bool text) override {
    auto it = cons.find(id);
    if (it == cons.end()) return false;
    const auto ec = it->second->send(
        data, size, text ? websocketpp::frame::opcode::text : websocketpp::frame::opcode::binary);
    return !ec;
  }
  std::size_t buffered(ClientId id) const override {
    auto it = cons.find(id);
    return it == cons.end() ? 0 : it->second->get_buffered_amount();
  }
  void stop() override;
};

template <class Config>
void ServerImpl<Config>::install_handlers() {
  auto& s = server;
  s.clear_access_channels(websocketpp::log::alevel::all);
  s.clear_error_channels(websocketpp::log::elevel::all);
  s.init_asio();
  s.set_reuse_addr(true);
  s.set_validate_handler([this](Hdl h) { return validate(h); });
  s.set_http_handler([this](Hdl h) { http(h); });
  s.set_open_handler([this](Hdl h) {
    const ClientId id = next_id++;
    auto con = server.get_con_from_hdl(h);
    ids[h] = id;
    cons[id] = con;
    handlers.open(id, con->get_remote_endpoint());
  });
  s.set_close_handler([this](Hdl h) {
    auto it = ids.find(h);
    if (it == ids.end()) return;
    const ClientId id = it->second;
    ids.erase(it);
    cons.erase(id);
    handlers.close(id);
  });
  s.set_message_handler([this](Hdl h, typename Server::message_ptr m) {
    auto it = ids.find(h);
    if (it == ids.end()) return;
    handlers.message(it->second, m->get_opcode() == websocketpp::frame::opcode::text,
                     m->get_payload());
  });
}

template <class Config>
void ServerImpl<Config>::listen(const std::string& address, int port) {
  auto& s = server;
  asio::error_code ec;
  const auto addr = asio::ip::make_address(address, ec);
  if (ec) throw std::runtime_error("'" + address + "' is not an IP address");
  s.listen(asio::ip::tcp::endpoint(addr, static_cast<std::uint16_t>(port)), ec);
  if (ec) {
    throw std::runtime_error("cannot listen on " + address + ":" + std::to_string(port) + ": " +
                             ec.message());
  }
  s.start_accept(ec);
  if (ec) throw std::runtime_error("cannot accept on " + address + ": " + ec.message());
  port_ = s.get_local_endpoint(ec).port();
  timer = std::make_unique<asio::steady_timer>(s.get_io_service());
}

template <class Config>
void ServerImpl<Config>::stop() {
  if (stopped) return;
  stopped = true;
  if (!thread.joinable()) return;
  post([this] {
    websocketpp::lib::error_code ec;
    server.stop_listening(ec);
    timer->cancel();
    for (auto& [id, con] : cons) {
      con->close(websocketpp::close::status::going_away, "teleop_bridge stops", ec);
    }
  });
  // the closing handshakes get a moment, then the loop stops whatever is left
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  server.stop();
  thread.join();
}

using SslContext = asio::ssl::context;

/// The TLS context of --tls-cert/--tls-key. @throws std::invalid_argument naming the file.
std::shared_ptr<SslContext> make_tls_context(const WsAccess& a) {
  for (const auto* f : {&a.tls_cert_file, &a.tls_key_file}) {
    if (!readable(*f)) throw std::invalid_argument("cannot read '" + *f + "'");
  }
  auto ctx = std::make_shared<SslContext>(SslContext::tls_server);
  asio::error_code ec;
  ctx->set_options(SslContext::default_workarounds | SslContext::no_sslv2 | SslContext::no_sslv3 |
                       SslContext::no_tlsv1 | SslContext::no_tlsv1_1 | SslContext::single_dh_use,
                   ec);
  ctx->use_certificate_chain_file(a.tls_cert_file, ec);
  if (ec) {
    throw std::invalid_argument("'" + a.tls_cert_file +
                                "' is not a PEM certificate (chain): " + ec.message());
  }
  ctx->use_private_key_file(a.tls_key_file, SslContext::pem, ec);
  if (ec) {
    throw std::invalid_argument("'" + a.tls_key_file +
                                "' is not the PEM private key of the certificate: " + ec.message());
  }
  return ctx;
}

template <class Config>
std::unique_ptr<WsServer::Impl> make_impl(const std::string& address, int port,
                                          const std::string& subprotocol, std::size_t max_bytes,
                                          int tick_ms, const WsAccess& access, WsHandlers h) {
  auto im = std::make_unique<ServerImpl<Config>>();
  im->handlers = std::move(h);
  im->access = access;
  im->subprotocol = subprotocol;
  im->tick_ms = tick_ms;
  im->install_handlers();
  im->server.set_max_message_size(max_bytes);
  if constexpr (!std::is_same_v<Config, websocketpp::config::asio>) {
    auto ctx = make_tls_context(access);
    im->server.set_tls_init_handler([ctx](Hdl) { return ctx; });
  }
  im->listen(address, port);
  return im;
}

}  // namespace

WsServer::WsServer(const std::string& address, int port, const std::string& subprotocol,
                   std::size_t max_message_bytes, int tick_ms, const WsAccess& access,
                   WsHandlers handlers) {
  if (access.tls_cert_file.empty() != access.tls_key_file.empty()) {
    throw std::invalid_argument("TLS needs both a certificate and its key");
  }
  if (access.tls_cert_file.empty()) {
    impl_ = make_impl<websocketpp::config::asio>(address, port, subprotocol, max_message_bytes,
                                                 tick_ms, access, std::move(handlers));
  } else {
    impl_ = make_impl<websocketpp::config::asio_tls>(address, port, subprotocol, max_message_bytes,
                                                     tick_ms, access, std::move(handlers));
  }
}

WsServer::~WsServer() {
  try {
    stop();
  } catch (...) {
  }
}

int WsServer::port() const { return impl_->port(); }
void WsServer::start() { impl_->start(); }
void WsServer::post(std::function<void()> fn) { impl_->post(std::move(fn)); }
bool WsServer::send(ClientId id, const void* data, std::size_t size, bool text) {
  return impl_->send(id, data, size, text);
}
std::size_t WsServer::buffered(ClientId id) const { return impl_->buffered(id); }
void WsServer::stop() { impl_->stop(); }

}  // namespace teleop::bridge
