// The bridge's per-client send queue (bounded; mesh frames dropped first, every drop counted;
// no allocation once warm) and its parsing of client messages (subscribe, unsubscribe; anything
// else refused with a reason, never a crash).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "client/bridge/client_queue.hpp"
#include "client/bridge/ws_protocol.hpp"
#include "tests/support/alloc_counter.hpp"

namespace teleop::bridge {
namespace {

std::vector<std::uint8_t> bytes(std::size_t n, std::uint8_t v) {
  return std::vector<std::uint8_t>(n, v);
}

TEST(ClientQueue, MeshFramesGoFirstAndTheBoundHolds) {
  ClientQueue q(10'000, 2);
  const auto head = bytes(13, 1);
  const auto mesh = bytes(3000, 2);
  const auto state = bytes(300, 3);
  q.push(FrameClass::kBulk, 0, head, mesh);
  q.push(FrameClass::kBulk, 0, head, mesh);  // replaces the first
  EXPECT_EQ(q.counts().dropped_bulk, 1u);
  q.push(FrameClass::kBulk, 1, head, mesh);
  for (int i = 0; i < 40; ++i) {
    q.push(FrameClass::kKept, 0, head, state);
    EXPECT_LE(q.bytes(), q.bound());
  }
  // 40 state frames of 313 bytes (12 520) do not fit in 10 000: both mesh frames went first
  EXPECT_EQ(q.counts().dropped_bulk, 3u);
  EXPECT_GT(q.counts().dropped_kept, 0u);
  EXPECT_LE(q.bytes(), 10'000u);
  // kept frames come out in order, the newest kept
  std::size_t n = 0;
  while (const auto* f = q.front()) {
    EXPECT_EQ(f->size(), 313u);
    q.pop();
    ++n;
  }
  EXPECT_EQ(n + q.counts().dropped_kept, 40u);
  EXPECT_EQ(q.bytes(), 0u);
  EXPECT_TRUE(q.empty());
  q.push(FrameClass::kKept, 0, head, bytes(20'000, 4));
  EXPECT_EQ(q.counts().too_large, 1u);
  EXPECT_TRUE(q.empty());
}

TEST(ClientQueue, WarmQueueDoesNotAllocate) {
  ClientQueue q(1u << 20, 1, 64);
  const auto head = bytes(13, 1);
  const auto mesh = bytes(30'000, 2);
  const auto state = bytes(400, 3);
  for (int round = 0; round < 3; ++round) {  // warm every slot
    for (int i = 0; i < 64; ++i) q.push(FrameClass::kKept, 0, head, state);
    q.push(FrameClass::kBulk, 0, head, mesh);
    while (q.front()) q.pop();
  }
  test::NoAllocScope scope;
  for (int i = 0; i < 1000; ++i) {
    q.push(FrameClass::kKept, 0, head, state);
    q.push(FrameClass::kBulk, 0, head, mesh);
    if (i % 3 == 0) q.pop();
  }
  EXPECT_EQ(scope.allocations(), 0u);
}

TEST(ClientQueue, MemoryKeptBySlotsIsBounded) {
  // 4096 kept slots, each of which may once have held a large frame: the slots' capacity must
  // not add up beyond the bound (a client that reads slowly, frames of every size)
  const std::size_t bound = 256u << 10;
  ClientQueue q(bound, 2);
  const auto head = bytes(13, 1);
  for (int i = 0; i < 20'000; ++i) {
    const std::size_t n = 100 + static_cast<std::size_t>(i % 7) * 9000;  // 100 B .. 54 KB
    q.push(FrameClass::kKept, 0, head, bytes(n, 5));
    if (i % 2 == 0)
      q.push(FrameClass::kBulk, static_cast<std::size_t>(i % 4 / 2), head, bytes(30'000, 6));
    if (i % 5 == 0) q.pop();
    ASSERT_LE(q.bytes(), bound);
    ASSERT_LE(q.retained_bytes(), 3 * bound) << "after " << i << " frames";
  }
}

TEST(ClientRequest, SubscribeAndUnsubscribeParse) {
  auto r = parse_client_request(
      R"({"op":"subscribe","subscriptions":[{"id":7,"channelId":2},{"id":8,"channelId":3}]})");
  ASSERT_EQ(r.kind, ClientRequest::Kind::kSubscribe);
  ASSERT_EQ(r.subscribe.size(), 2u);
  EXPECT_EQ(r.subscribe[1].id, 8u);
  EXPECT_EQ(r.subscribe[1].channel_id, 3u);
  r = parse_client_request(R"({"op":"unsubscribe","subscriptionIds":[7,8]})");
  ASSERT_EQ(r.kind, ClientRequest::Kind::kUnsubscribe);
  EXPECT_EQ(r.unsubscribe, (std::vector<std::uint32_t>{7, 8}));
}

TEST(ClientRequest, BadMessagesAreRefusedWithAReason) {
  for (const std::string& bad : std::vector<std::string>{
           "", "{", "[]", "null", "{\"op\":3}", "{\"op\":\"subscribe\"}",
           R"({"op":"subscribe","subscriptions":[{"id":-1,"channelId":2}]})",
           R"({"op":"subscribe","subscriptions":[{"id":1.5,"channelId":2}]})",
           R"({"op":"subscribe","subscriptions":[{"id":4294967296,"channelId":2}]})",
           R"({"op":"unsubscribe","subscriptionIds":["a"]})",
           std::string(100, '[') + "1" + std::string(100, ']'),
           "{\"op\":\"subscribe\"} trailing"}) {
    const auto r = parse_client_request(bad);
    EXPECT_EQ(r.kind, ClientRequest::Kind::kInvalid) << bad;
    EXPECT_FALSE(r.error.empty()) << bad;
  }
  const auto r = parse_client_request(R"({"op":"advertise","channels":[]})");
  EXPECT_EQ(r.kind, ClientRequest::Kind::kUnsupported);
  EXPECT_EQ(r.op, "advertise");
}

TEST(WsProtocol, MessageDataHeaderIsLittleEndian) {
  std::uint8_t h[kMessageDataHeader];
  message_data_header(h, 0x01020304u, 0x1112131415161718ull);
  EXPECT_EQ(h[0], 0x01);
  EXPECT_EQ(h[1], 0x04);
  EXPECT_EQ(h[4], 0x01);
  EXPECT_EQ(h[5], 0x18);
  EXPECT_EQ(h[12], 0x11);
  const std::string adv = advertise_json({{3, "teleop/scene", "teleop::SceneDescription", "x"}});
  EXPECT_NE(adv.find("\"schemaEncoding\":\"omgidl\""), std::string::npos) << adv;
  EXPECT_NE(adv.find("\"encoding\":\"cdr\""), std::string::npos) << adv;
}

}  // namespace
}  // namespace teleop::bridge
