#pragma once
// The Foxglove WebSocket protocol (subprotocol foxglove.websocket.v1) as teleop_bridge speaks
// it: the server's JSON text messages (serverInfo, advertise, status), the binary messageData
// header, and the parsing of what a client sends (subscribe, unsubscribe; anything else is
// refused with a status message, never acted on).
#include <cstdint>
#include <string>
#include <vector>

namespace teleop::bridge {

inline constexpr const char* kSubprotocol = "foxglove.websocket.v1";
inline constexpr std::uint8_t kOpMessageData = 0x01;
/// Size of the binary messageData header: opcode, u32 subscription id, u64 receive time [ns].
inline constexpr std::size_t kMessageDataHeader = 13;

struct Channel {
  std::uint32_t id = 0;
  std::string topic;                       ///< e.g. "teleop/slave_state"
  std::string schema_name;                 ///< the type's full name, e.g. "teleop::SlaveState"
  std::string schema;                      ///< the IDL text that defines it (or the JSON schema)
  std::string encoding = "cdr";            ///< "cdr" or "json"
  std::string schema_encoding = "omgidl";  ///< "omgidl" or "jsonschema"
};

enum class StatusLevel { kInfo = 0, kWarning = 1, kError = 2 };

std::string server_info_json(const std::string& name, const std::string& session_id);
std::string advertise_json(const std::vector<Channel>& channels);
std::string status_json(StatusLevel level, const std::string& message);

/// Writes the messageData header (little-endian) into `out` (kMessageDataHeader bytes).
void message_data_header(std::uint8_t* out, std::uint32_t subscription_id,
                         std::uint64_t receive_ns);

struct Subscription {
  std::uint32_t id = 0;
  std::uint32_t channel_id = 0;
};

/// A client's text message, parsed and checked.
struct ClientRequest {
  enum class Kind { kSubscribe, kUnsubscribe, kUnsupported, kInvalid } kind = Kind::kInvalid;
  std::vector<Subscription> subscribe;
  std::vector<std::uint32_t> unsubscribe;
  std::string op;     ///< the op named (kUnsupported), when there was one
  std::string error;  ///< why it is invalid (kInvalid): names the field and the value
};

/// Parses a client's text message (strict JSON, nesting at most 16 deep).
ClientRequest parse_client_request(const std::string& text);

}  // namespace teleop::bridge
