#include "client/bridge/ws_server.hpp"

#include <chrono>
#include <map>
#include <stdexcept>
#include <thread>
#include <vector>
#include <websocketpp/config/asio_no_tls.hpp>
#include <websocketpp/server.hpp>

namespace teleop::bridge {

using Server = websocketpp::server<websocketpp::config::asio>;
using Hdl = websocketpp::connection_hdl;
namespace asio = websocketpp::lib::asio;

struct WsServer::Impl {
  Server server;
  WsHandlers handlers;
  std::string subprotocol;
  int tick_ms = 20;
  int port = 0;
  std::unique_ptr<asio::steady_timer> timer;
  std::map<Hdl, ClientId, std::owner_less<Hdl>> ids;  // server thread only
  std::map<ClientId, Server::connection_ptr> cons;    // server thread only
  ClientId next_id = 1;
  std::thread thread;
  bool stopped = false;

  bool validate(Hdl hdl) {
    auto con = server.get_con_from_hdl(hdl);
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
  void arm() {
    timer->expires_after(std::chrono::milliseconds(tick_ms));
    timer->async_wait([this](const asio::error_code& ec) {
      if (ec) return;
      handlers.tick();
      arm();
    });
  }
};

WsServer::WsServer(const std::string& address, int port, const std::string& subprotocol,
                   std::size_t max_message_bytes, int tick_ms, WsHandlers handlers)
    : impl_(std::make_unique<Impl>()) {
  auto& s = impl_->server;
  impl_->handlers = std::move(handlers);
  impl_->subprotocol = subprotocol;
  impl_->tick_ms = tick_ms;
  s.clear_access_channels(websocketpp::log::alevel::all);
  s.clear_error_channels(websocketpp::log::elevel::all);
  s.init_asio();
  s.set_reuse_addr(true);
  s.set_max_message_size(max_message_bytes);
  Impl* im = impl_.get();
  s.set_validate_handler([im](Hdl h) { return im->validate(h); });
  s.set_open_handler([im](Hdl h) {
    const ClientId id = im->next_id++;
    auto con = im->server.get_con_from_hdl(h);
    im->ids[h] = id;
    im->cons[id] = con;
    im->handlers.open(id, con->get_remote_endpoint());
  });
  s.set_close_handler([im](Hdl h) {
    auto it = im->ids.find(h);
    if (it == im->ids.end()) return;
    const ClientId id = it->second;
    im->ids.erase(it);
    im->cons.erase(id);
    im->handlers.close(id);
  });
  s.set_message_handler([im](Hdl h, Server::message_ptr m) {
    auto it = im->ids.find(h);
    if (it == im->ids.end()) return;
    im->handlers.message(it->second, m->get_opcode() == websocketpp::frame::opcode::text,
                         m->get_payload());
  });
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
  impl_->port = s.get_local_endpoint(ec).port();
  impl_->timer = std::make_unique<asio::steady_timer>(s.get_io_service());
}

WsServer::~WsServer() {
  try {
    stop();
  } catch (...) {
  }
}

int WsServer::port() const { return impl_->port; }

void WsServer::start() {
  impl_->arm();
  impl_->thread = std::thread([this] { impl_->server.run(); });
}

void WsServer::post(std::function<void()> fn) {
  asio::post(impl_->server.get_io_service(), std::move(fn));
}

bool WsServer::send(ClientId id, const void* data, std::size_t size, bool text) {
  auto it = impl_->cons.find(id);
  if (it == impl_->cons.end()) return false;
  const auto ec = it->second->send(
      data, size, text ? websocketpp::frame::opcode::text : websocketpp::frame::opcode::binary);
  return !ec;
}

std::size_t WsServer::buffered(ClientId id) const {
  auto it = impl_->cons.find(id);
  return it == impl_->cons.end() ? 0 : it->second->get_buffered_amount();
}

void WsServer::stop() {
  if (impl_->stopped) return;
  impl_->stopped = true;
  if (!impl_->thread.joinable()) return;
  Impl* im = impl_.get();
  post([im] {
    websocketpp::lib::error_code ec;
    im->server.stop_listening(ec);
    im->timer->cancel();
    for (auto& [id, con] : im->cons) {
      con->close(websocketpp::close::status::going_away, "teleop_bridge stops", ec);
    }
  });
  // the closing handshakes get a moment, then the loop stops whatever is left
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  impl_->server.stop();
  impl_->thread.join();
}

}  // namespace teleop::bridge
