#pragma once
// A WebSocket server on websocketpp + asio, reduced to what the bridge needs: clients by
// number, text and binary messages, the bytes a client's socket has not taken yet, a periodic
// tick, all on one thread; plain or TLS; plain HTTP GETs answered by a page handler; an
// optional access token required on every request. websocketpp 0.8 does not compile as C++20
// (template-ids as constructor names), so it lives in ws_server.cpp alone, compiled as C++17; this
// header keeps to C++17 as well.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

namespace teleop::bridge {

using ClientId = std::uint64_t;

/// How a client must come in.
struct WsAccess {
  std::string tls_cert_file, tls_key_file;  ///< both empty: plain TCP
  std::string token;  ///< non-empty: required as ?token=... or "Authorization: Bearer ..."
};

/// The answer to a plain HTTP GET (not an upgrade).
struct HttpReply {
  int status = 404;
  std::string content_type = "text/plain; charset=utf-8";
  std::string body = "not found\n";
};

struct WsHandlers {
  /// Called before the handshake completes; false refuses the client (503).
  std::function<bool()> accept;
  std::function<void(ClientId, const std::string& remote)> open;
  std::function<void(ClientId)> close;
  std::function<void(ClientId, bool text, const std::string& payload)> message;
  /// Called every tick_ms.
  std::function<void()> tick;
  /// A plain HTTP GET of `path` (query removed), after the token check.
  std::function<HttpReply(const std::string& path)> http;
  /// A request refused for a missing or wrong token (answered 401).
  std::function<void(const std::string& remote)> unauthorized;
};

class WsServer {
 public:
  /// Listens on address:port (port 0: the system picks one) for clients offering
  /// `subprotocol`. @throws std::invalid_argument naming the file when a TLS file cannot be
  /// used, std::runtime_error naming the address when it cannot listen.
  WsServer(const std::string& address, int port, const std::string& subprotocol,
           std::size_t max_message_bytes, int tick_ms, const WsAccess& access, WsHandlers handlers);
  ~WsServer();
  WsServer(const WsServer&) = delete;
  WsServer& operator=(const WsServer&) = delete;

  int port() const;
  /// Starts the server thread.
  void start();
  /// Runs `fn` on the server thread.
  void post(std::function<void()> fn);
  /// Server thread only: queues a message to a client; false when it is gone or failed.
  bool send(ClientId id, const void* data, std::size_t size, bool text);
  /// Server thread only: bytes queued to a client not yet written to its socket.
  std::size_t buffered(ClientId id) const;
  /// Closes every connection (going away) and stops the thread. Idempotent.
  void stop();

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// True when `header` ("Authorization" value) or the query of `resource` carries `token`
/// (compared in constant time). Exposed for the unit test.
bool token_matches(const std::string& token, const std::string& resource,
                   const std::string& header);

}  // namespace teleop::bridge
