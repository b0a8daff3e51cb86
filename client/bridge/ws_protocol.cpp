#include "client/bridge/ws_protocol.hpp"

#include <json/json.h>

#include <memory>
#include <sstream>
#include <stdexcept>

namespace teleop::bridge {

namespace {
std::string to_text(const Json::Value& v) {
  Json::StreamWriterBuilder w;
  w["indentation"] = "";
  return Json::writeString(w, v);
}

/// A JSON number that is a whole number in 0..2^32-1, or false.
bool as_u32(const Json::Value& v, std::uint32_t& out) {
  if (!v.isNumeric() || !v.isIntegral() || !v.isUInt()) return false;
  out = v.asUInt();
  return true;
}
}  // namespace

std::string server_info_json(const std::string& name, const std::string& session_id) {
  Json::Value v(Json::objectValue);
  v["op"] = "serverInfo";
  v["name"] = name;
  // read-only: no clientPublish, no parameters, no services
  v["capabilities"] = Json::Value(Json::arrayValue);
  v["supportedEncodings"] = Json::Value(Json::arrayValue);
  v["metadata"] = Json::Value(Json::objectValue);
  v["sessionId"] = session_id;
  return to_text(v);
}

std::string advertise_json(const std::vector<Channel>& channels) {
  Json::Value v(Json::objectValue);
  v["op"] = "advertise";
  Json::Value list(Json::arrayValue);
  for (const auto& c : channels) {
    Json::Value ch(Json::objectValue);
    ch["id"] = c.id;
    ch["topic"] = c.topic;
    ch["encoding"] = c.encoding;
    ch["schemaName"] = c.schema_name;
    ch["schema"] = c.schema;
    ch["schemaEncoding"] = c.schema_encoding;
    list.append(ch);
  }
  v["channels"] = list;
  return to_text(v);
}

std::string status_json(StatusLevel level, const std::string& message) {
  Json::Value v(Json::objectValue);
  v["op"] = "status";
  v["level"] = static_cast<int>(level);
  v["message"] = message;
  return to_text(v);
}

void message_data_header(std::uint8_t* out, std::uint32_t subscription_id,
                         std::uint64_t receive_ns) {
  out[0] = kOpMessageData;
  for (int i = 0; i < 4; ++i) out[1 + i] = static_cast<std::uint8_t>(subscription_id >> (8 * i));
  for (int i = 0; i < 8; ++i) out[5 + i] = static_cast<std::uint8_t>(receive_ns >> (8 * i));
}

namespace {
ClientRequest invalid(const std::string& why) {
  ClientRequest r;
  r.kind = ClientRequest::Kind::kInvalid;
  r.error = why;
  return r;
}

ClientRequest parse_subscribe(const Json::Value& v) {
  const Json::Value& subs = v["subscriptions"];
  if (!subs.isArray()) return invalid("subscribe: field 'subscriptions' must be an array");
  ClientRequest r;
  r.kind = ClientRequest::Kind::kSubscribe;
  for (Json::ArrayIndex i = 0; i < subs.size(); ++i) {
    const Json::Value& s = subs[i];
    Subscription sub;
    if (!s.isObject() || !as_u32(s["id"], sub.id) || !as_u32(s["channelId"], sub.channel_id)) {
      return invalid("subscribe: subscriptions[" + std::to_string(i) +
                     "] needs 'id' and 'channelId', whole numbers 0-4294967295");
    }
    r.subscribe.push_back(sub);
  }
  return r;
}

ClientRequest parse_unsubscribe(const Json::Value& v) {
  const Json::Value& ids = v["subscriptionIds"];
  if (!ids.isArray()) return invalid("unsubscribe: field 'subscriptionIds' must be an array");
  ClientRequest r;
  r.kind = ClientRequest::Kind::kUnsubscribe;
  for (Json::ArrayIndex i = 0; i < ids.size(); ++i) {
    std::uint32_t id = 0;
    if (!as_u32(ids[i], id)) {
      return invalid("unsubscribe: subscriptionIds[" + std::to_string(i) +
                     "] must be a whole number 0-4294967295");
    }
    r.unsubscribe.push_back(id);
  }
  return r;
}
}  // namespace

ClientRequest parse_client_request(const std::string& text) {
  Json::CharReaderBuilder b;
  Json::CharReaderBuilder::strictMode(&b.settings_);
  b["stackLimit"] = 16;
  std::unique_ptr<Json::CharReader> reader(b.newCharReader());
  Json::Value v;
  std::string errs;
  try {
    if (!reader->parse(text.data(), text.data() + text.size(), &v, &errs)) {
      std::string first = errs.substr(0, errs.find('\n'));
      return invalid("not valid JSON: " + first);
    }
  } catch (const std::exception& e) {
    // jsoncpp throws past its nesting limit
    return invalid(std::string("not valid JSON: ") + e.what());
  }
  if (!v.isObject()) return invalid("a client message must be a JSON object");
  const Json::Value& op = v["op"];
  if (!op.isString()) return invalid("field 'op' must be a string");
  const std::string name = op.asString();
  if (name == "subscribe") return parse_subscribe(v);
  if (name == "unsubscribe") return parse_unsubscribe(v);
  ClientRequest r;
  r.kind = ClientRequest::Kind::kUnsupported;
  r.op = name.substr(0, 64);
  return r;
}

}  // namespace teleop::bridge
