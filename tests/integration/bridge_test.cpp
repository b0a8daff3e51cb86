// teleop_bridge: a live session served over the Foxglove WebSocket protocol.
// A client sees serverInfo (read-only: no clientPublish) and one advertised channel per topic
// with its IDL as an omgidl schema, receives the latched scene at once and messageData whose
// payloads are CDR as DDS sent it, and gets status messages (never a crash) for bad JSON and
// for ops the bridge does not serve. A client that never reads costs bounded memory: its mesh
// frames are dropped and counted while another client keeps receiving.
#include <gtest/gtest.h>

#ifndef TELEOP_HAVE_BRIDGE
TEST(Bridge, Skipped) {
  GTEST_SKIP() << "teleop_bridge is not built (libwebsocketpp-dev, libasio-dev, libjsoncpp-dev)";
}
#else
#include <json/json.h>

#include <chrono>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <thread>

#include "tests/support/domains.hpp"
#include "tests/support/integration.hpp"
#include "tests/support/process.hpp"
#include "tests/support/ws_client.hpp"

namespace teleop::test {
namespace {

const std::string kBridgeBinary = std::string(TELEOP_BINARY_DIR) + "/client/teleop_bridge";

/// Waits for the bridge's "ws://127.0.0.1:PORT" line; 0 if it did not come.
int bridge_port(const Process& bridge) {
  const std::regex re("ws://127\\.0\\.0\\.1:([0-9]+)");
  for (int i = 0; i < 300; ++i) {
    std::smatch m;
    const std::string out = bridge.out();
    if (std::regex_search(out, m, re)) return std::stoi(m[1]);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return 0;
}

Json::Value parse(const std::string& text) {
  Json::Value v;
  Json::CharReaderBuilder b;
  std::string errs;
  std::istringstream in(text);
  EXPECT_TRUE(Json::parseFromStream(b, in, &v, &errs)) << text.substr(0, 200);
  return v;
}

/// Resident memory of a process [KiB] (VmRSS), 0 if unreadable.
long rss_kib(pid_t pid) {
  std::ifstream f("/proc/" + std::to_string(pid) + "/status");
  std::string line;
  while (std::getline(f, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stol(line.substr(6));
  }
  return 0;
}

/// Reads serverInfo and advertise; returns channel id -> topic.
std::map<std::uint32_t, std::string> handshake(WsClient& ws) {
  std::map<std::uint32_t, std::string> channels;
  auto info = ws.read(5000);
  EXPECT_TRUE(info && info->opcode == 1);
  if (!info) return channels;
  const Json::Value si = parse(info->text());
  EXPECT_EQ(si["op"].asString(), "serverInfo");
  for (const auto& c : si["capabilities"]) EXPECT_NE(c.asString(), "clientPublish");
  auto adv = ws.read(5000);
  EXPECT_TRUE(adv && adv->opcode == 1);
  if (!adv) return channels;
  const Json::Value a = parse(adv->text());
  EXPECT_EQ(a["op"].asString(), "advertise");
  for (const auto& ch : a["channels"]) {
    const std::string topic = ch["topic"].asString();
    const std::string type = ch["schemaName"].asString();
    if (topic.rfind("bridge/", 0) == 0) {
      // the bridge's own channels: JSON with a JSON schema (foxglove.SceneUpdate, ...)
      EXPECT_EQ(ch["encoding"].asString(), "json") << topic;
      EXPECT_EQ(ch["schemaEncoding"].asString(), "jsonschema") << topic;
      EXPECT_EQ(parse(ch["schema"].asString())["title"].asString(), type) << topic;
      channels[ch["id"].asUInt()] = topic;
      continue;
    }
    EXPECT_EQ(ch["encoding"].asString(), "cdr") << topic;
    EXPECT_EQ(ch["schemaEncoding"].asString(), "omgidl") << topic;
    EXPECT_EQ(type.rfind("teleop::", 0), 0u) << topic << " " << type;
    if (type.size() < 9) continue;
    const std::string schema = ch["schema"].asString();
    EXPECT_NE(schema.find("module teleop"), std::string::npos) << topic;
    EXPECT_NE(schema.find("struct " + type.substr(8)), std::string::npos) << topic;
    channels[ch["id"].asUInt()] = topic;
  }
  return channels;
}

std::string subscribe_all(const std::map<std::uint32_t, std::string>& channels) {
  std::string s = "{\"op\":\"subscribe\",\"subscriptions\":[";
  for (const auto& [id, topic] : channels) {
    s += (s.back() == '[' ? "" : ",") + std::string("{\"id\":") + std::to_string(id + 100) +
         ",\"channelId\":" + std::to_string(id) + "}";
  }
  return s + "]}";
}

std::uint64_t le(const std::uint8_t* p, int n) {
  std::uint64_t v = 0;
  for (int i = n - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

/// A status answering a client's request. On a loaded machine a client may also be told, once a
/// second, that it reads too slowly (frames dropped): that is not an answer.
bool answers_a_request(const Json::Value& s) {
  return s["op"].asString() == "status" &&
         s["message"].asString().find("reads too slowly") == std::string::npos;
}

TEST(Bridge, ServesEveryTopicAsCdrWithOmgidlSchemas) {
  const std::string d = std::to_string(domains::kBridgeSession);
  Process server(kServerBinary, {"--domain", d, "--duration", "60", "--quiet"}, "bridge_srv");
  Process bridge(kBridgeBinary, {"--domain", d, "--port", "0", "--stats-s", "1"}, "bridge_br");
  const int port = bridge_port(bridge);
  ASSERT_GT(port, 0) << bridge.err();
  Process master(kMasterBinary, {"--domain", d, "--duration", "8", "--homing", "0.5", "--quiet"},
                 "bridge_master");
  std::this_thread::sleep_for(std::chrono::seconds(2));  // the scene is latched by now
  WsClient refused(port, "not.foxglove");
  EXPECT_FALSE(refused.ok()) << "a client without the subprotocol is refused";
  WsClient ws(port, "foxglove.websocket.v1");
  ASSERT_TRUE(ws.ok()) << ws.response();
  const auto channels = handshake(ws);
  std::set<std::string> topics;
  for (const auto& [id, t] : channels) topics.insert(t);
  for (const char* t : {"teleop/scene", "teleop/mesh_topology", "teleop/mesh_frame",
                        "teleop/events", "teleop/server_stats", "teleop/slave_state_view",
                        "teleop/master_state_view", "teleop/slave_state_monitor"}) {
    EXPECT_TRUE(topics.count(t)) << t << " is not advertised";
  }
  EXPECT_FALSE(topics.count("teleop/slave_state")) << "1 kHz topics only with --full-rate";
  ASSERT_TRUE(ws.send(subscribe_all(channels)));
  ASSERT_TRUE(ws.send("{not json"));
  ASSERT_TRUE(ws.send("{\"op\":\"advertise\",\"channels\":[]}"));
  ASSERT_TRUE(ws.send("{\"op\":\"subscribe\",\"subscriptions\":[{\"id\":1,\"channelId\":999}]}"));
  std::map<std::string, int> got;
  std::vector<std::string> statuses;
  std::uint64_t last_state_ns = 0;
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(4);
  while (std::chrono::steady_clock::now() < end) {
    auto f = ws.read(2000);
    ASSERT_TRUE(f) << "the bridge stopped sending";
    if (f->opcode == 1) {
      const Json::Value s = parse(f->text());
      if (answers_a_request(s)) statuses.push_back(f->text());
      continue;
    }
    ASSERT_EQ(f->opcode, 2);
    ASSERT_GE(f->payload.size(), 13u + 4u);
    ASSERT_EQ(f->payload[0], 0x01);
    const auto sub = static_cast<std::uint32_t>(le(&f->payload[1], 4));
    ASSERT_TRUE(channels.count(sub - 100)) << "unknown subscription id " << sub;
    const std::string& topic = channels.at(sub - 100);
    const std::uint64_t ns = le(&f->payload[5], 8);
    EXPECT_GT(ns, 1'600'000'000'000'000'000ull) << topic;  // a wall-clock time, after 2020
    if (topic.rfind("bridge/", 0) == 0) {
      EXPECT_EQ(f->payload[13], '{') << topic << ": a JSON object";
      ++got[topic];
      continue;
    }
    // the CDR encapsulation header: 0x00 0x00 (big endian) or 0x00 0x01 (little endian), options
    EXPECT_EQ(f->payload[13], 0) << topic;
    EXPECT_LE(f->payload[14], 1) << topic;
    if (topic == "teleop/slave_state_view") {
      EXPECT_GE(ns, last_state_ns);
      last_state_ns = ns;
    }
    ++got[topic];
  }
  EXPECT_GE(got["teleop/scene"], 1) << "the latched scene reaches a late subscriber";
  EXPECT_GE(got["teleop/mesh_topology"], 1);
  EXPECT_GE(got["teleop/mesh_frame"], 10);
  EXPECT_GE(got["teleop/slave_state_view"], 10);
  EXPECT_GE(got["teleop/master_state_view"], 10);
  EXPECT_GE(got["bridge/scene"], 10) << "the 3-D scene at the visual rate";
  EXPECT_GE(got["bridge/transforms"], 10);
  EXPECT_GE(got["bridge/plot"], 10);
  ASSERT_EQ(statuses.size(), 3u) << "a status for each bad message";
  EXPECT_NE(statuses[0].find("\"level\":2"), std::string::npos) << statuses[0];
  EXPECT_NE(statuses[0].find("not valid JSON"), std::string::npos) << statuses[0];
  EXPECT_NE(statuses[1].find("read-only"), std::string::npos) << statuses[1];
  EXPECT_NE(statuses[2].find("channelId 999"), std::string::npos) << statuses[2];
  bridge.signal(SIGINT);
  EXPECT_EQ(bridge.wait_for(10.0), 0) << bridge.err();
  EXPECT_NE(bridge.err().find("bad requests 3"), std::string::npos) << bridge.err();
}

TEST(Bridge, ClientThatNeverReadsCostsBoundedMemory) {
  const std::string d = std::to_string(domains::kBridgeSlowClient);
  Process server(kServerBinary, {"--domain", d, "--duration", "60", "--quiet"}, "bridge_slow_srv");
  Process bridge(kBridgeBinary,
                 {"--domain", d, "--port", "0", "--stats-s", "1", "--queue-kb", "256"},
                 "bridge_slow_br");
  const int port = bridge_port(bridge);
  ASSERT_GT(port, 0) << bridge.err();
  Process master(kMasterBinary, {"--domain", d, "--duration", "14", "--homing", "0.5", "--quiet"},
                 "bridge_slow_master");
  WsClient slow(port, "foxglove.websocket.v1", 4096);
  ASSERT_TRUE(slow.ok());
  std::map<std::uint32_t, std::string> channels;
  for (std::uint32_t id = 1; id <= 11; ++id) channels[id] = "";
  ASSERT_TRUE(slow.send(subscribe_all(channels)));  // and it never reads again
  std::this_thread::sleep_for(std::chrono::seconds(4));
  const long rss_early = rss_kib(bridge.pid());
  // a reading client meanwhile gets its state frames
  WsClient good(port, "foxglove.websocket.v1");
  ASSERT_TRUE(good.ok());
  const auto good_channels = handshake(good);
  ASSERT_TRUE(good.send(subscribe_all(good_channels)));
  int frames = 0;
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(6);
  while (std::chrono::steady_clock::now() < end) {
    if (auto f = good.read(2000); f && f->opcode == 2) ++frames;
  }
  EXPECT_GE(frames, 100) << "the reading client is served while the other one stalls";
  const long rss_late = rss_kib(bridge.pid());
  ASSERT_GT(rss_early, 0);
  // generous: 6 s of 30 KB mesh frames at 60 Hz is ~11 MB; the queue bound is 256 KiB
  EXPECT_LT(rss_late - rss_early, 8 * 1024)
      << "bridge RSS grew from " << rss_early << " to " << rss_late << " KiB";
  bridge.signal(SIGINT);
  EXPECT_EQ(bridge.wait_for(10.0), 0) << bridge.err();
  const std::string err = bridge.err();
  const std::regex re("client 1 [^;]*dropped ([0-9]+) mesh \\+ ([0-9]+) other, queued ([0-9]+)");
  std::smatch m;
  const auto done = err.find("done:");
  ASSERT_NE(done, std::string::npos) << err;
  const std::string summary = err.substr(done);
  ASSERT_TRUE(std::regex_search(summary, m, re)) << summary;
  EXPECT_GT(std::stoull(m[1]), 10u) << "the slow client's mesh frames are dropped and counted";
  EXPECT_NE(summary.find("client 2"), std::string::npos) << summary;
}

}  // namespace
}  // namespace teleop::test
#endif  // TELEOP_HAVE_BRIDGE
