#pragma once
// A WebSocket server on websocketpp + asio, reduced to what the bridge needs: clients by
// number, text and binary messages, the bytes a client's socket has not taken yet, a periodic
// tick, all on one thread. websocketpp 0.8 does not compile as C++20 (template-ids as
// constructor names), so it lives in ws_server.cpp alone, compiled as C++17; this header keeps
// to C++17 as well.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

namespace teleop::bridge {

using ClientId = std::uint64_t;

struct WsHandlers {
  /// Called before the handshake completes; false refuses the client (503).
  std::function<bool()> accept;
  std::function<void(ClientId, const std::string& remote)> open;
  std::function<void(ClientId)> close;
  std::function<void(ClientId, bool text, const std::string& payload)> message;
  /// Called every tick_ms.
  std::function<void()> tick;
};

class WsServer {
 public:
  /// Listens on address:port (port 0: the system picks one) for clients offering
  /// `subprotocol`. @throws std::runtime_error naming the address when it cannot listen.
  WsServer(const std::string& address, int port, const std::string& subprotocol,
           std::size_t max_message_bytes, int tick_ms, WsHandlers handlers);
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

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace teleop::bridge
