#pragma once
// The bridge behind teleop_bridge: a Foxglove WebSocket protocol server (ws_protocol.hpp, on
// websocketpp + asio, one thread) fed by raw DDS readers of the teleop/* topics (one thread,
// client/record/raw_reader.hpp), forwarding each sample's serialized CDR payload unchanged.
// Latched topics (transient local: scene, topology, tuning status, events) keep their last
// samples, sent at once to a client that subscribes late. Each client has a bounded send queue
// (client_queue.hpp): a slow client loses mesh frames first, then its oldest kept frames, each
// drop counted and reported to it in a status message; the bridge's memory does not grow with it.
// Read-only: clients can subscribe and unsubscribe, nothing else. It derives JSON channels for
// 3-D panels (foxglove.SceneUpdate, foxglove.FrameTransforms: scene_json.hpp) and serves its own
// page (web/index.html) to plain HTTP GETs of / on the same port.
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "client/bridge/ws_server.hpp"
#include "common/dds/participant.hpp"

namespace teleop::bridge {

struct BridgeOptions {
  std::string address = "127.0.0.1";   ///< listen address (loopback unless told otherwise)
  int port = 8765;                     ///< 0: the system picks one (see port())
  bool full_rate = false;              ///< also the 1 kHz topics (default: rate-limited copies)
  std::size_t queue_bytes = 4u << 20;  ///< per-client send queue bound [bytes]
  int max_clients = 32;
  double batch_ms = 10.0;  ///< the DDS thread takes samples this often [ms]
  WsAccess access;         ///< TLS files and the access token (empty: plain, no token)
};

/// Counts of one connected (or, in the summary, departed) client.
struct ClientCounts {
  int id = 0;
  std::string remote;
  std::uint64_t sent = 0, dropped_bulk = 0, dropped_kept = 0, too_large = 0;
  std::uint64_t bad_requests = 0;  ///< invalid JSON or fields, unsupported ops, binary messages
  std::size_t queued_bytes = 0;
  bool connected = true;
};

struct BridgeCounts {
  std::uint64_t samples = 0;  ///< DDS samples received
  std::uint64_t clients_total = 0, clients_refused = 0;
  std::uint64_t rejected = 0;
  std::uint64_t unauthorized = 0;  ///< requests refused for a missing or wrong access token
  std::uint64_t pages = 0;  ///< HTTP requests answered (the page)  ///< samples that did not decode
                            ///< or were not valid for the scene
  std::vector<ClientCounts> clients;  ///< connected ones, then the departed
};

class Bridge {
 public:
  /// Creates the readers and listens. @throws dds::DdsError, std::runtime_error (the port).
  Bridge(dds::Participant& participant, const BridgeOptions& options);
  ~Bridge();
  Bridge(const Bridge&) = delete;
  Bridge& operator=(const Bridge&) = delete;

  int port() const { return port_; }
  /// Topic names served, in channel id order (id = index + 1).
  std::vector<std::string> topics() const;
  BridgeCounts counts() const;
  /// Closes every connection, stops both threads. Idempotent.
  void stop();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  int port_ = 0;
};

/// One line of counts for stderr ("clients 2, samples 1234, client 1 127.0.0.1:5555 sent ...").
std::string counts_line(const BridgeCounts& c);

}  // namespace teleop::bridge
