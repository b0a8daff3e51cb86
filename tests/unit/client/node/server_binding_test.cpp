// A master believes one server: the first whose SlaveState arrives, bound by the grant of the
// slave to this master's session; other participants' states, stats and server events are
// ignored and counted; a new server takes over only after the bound one fell silent.
#include "client/node/server_binding.hpp"

#include <gtest/gtest.h>

namespace teleop::master {
namespace {

ServerBinding::Prefix prefix(std::uint8_t id) {
  ServerBinding::Prefix p;
  for (auto& b : p.value) b = 0;
  p.value[0] = 0x01;
  p.value[11] = id;
  return p;
}

constexpr std::uint32_t kMine = 0x1234;
constexpr std::int64_t kMs = 1'000'000;

TEST(ServerBinding, TheGrantBindsAndOthersAreIgnoredAndCounted) {
  ServerBinding b(kMine, 100 * kMs);
  EXPECT_FALSE(b.accept(ServerBinding::kStats, prefix(1)));  // no server yet: not counted
  EXPECT_EQ(b.foreign_total(), 0u);
  EXPECT_TRUE(b.accept_state(prefix(1), 0, false, 0));  // the first server seen
  EXPECT_FALSE(b.bound());
  EXPECT_TRUE(b.accept_state(prefix(1), kMine, true, 1 * kMs));  // the grant
  EXPECT_TRUE(b.bound());
  EXPECT_EQ(b.server(), "01000000.00000000.00000001");
  // a rogue naming this master's session, while the server is live
  EXPECT_FALSE(b.accept_state(prefix(9), kMine, true, 2 * kMs));
  EXPECT_FALSE(b.accept(ServerBinding::kStats, prefix(9)));
  EXPECT_FALSE(b.accept(ServerBinding::kEvent, prefix(9)));
  EXPECT_TRUE(b.accept(ServerBinding::kStats, prefix(1)));
  EXPECT_TRUE(b.accept(ServerBinding::kEvent, prefix(1)));
  EXPECT_EQ(b.foreign(ServerBinding::kState), 1u);
  EXPECT_EQ(b.foreign(ServerBinding::kStats), 1u);
  EXPECT_EQ(b.foreign(ServerBinding::kEvent), 1u);
  EXPECT_EQ(b.first_foreign(), "01000000.00000000.00000009");
  // the bound server reporting another owner is still the server
  EXPECT_TRUE(b.accept_state(prefix(1), 0x9999, true, 3 * kMs));
  EXPECT_EQ(b.rebinds(), 0u);
}

TEST(ServerBinding, AGrantFromAnotherServerBeforeBindingMovesThere) {
  ServerBinding b(kMine, 100 * kMs);
  EXPECT_TRUE(b.accept_state(prefix(1), 0, false, 0));
  EXPECT_FALSE(b.accept_state(prefix(2), 0, false, 1 * kMs));  // no grant: ignored
  EXPECT_TRUE(b.accept_state(prefix(2), kMine, true, 2 * kMs));
  EXPECT_TRUE(b.bound());
  EXPECT_FALSE(b.accept_state(prefix(1), 0, false, 3 * kMs));
  EXPECT_EQ(b.rebinds(), 0u);
}

TEST(ServerBinding, ARestartedServerTakesOverOnlyAfterTheBoundOneFellSilent) {
  ServerBinding b(kMine, 100 * kMs);
  EXPECT_TRUE(b.accept_state(prefix(1), kMine, true, 0));
  // the new server grants 50 ms after the bound one's last state: still ignored
  EXPECT_FALSE(b.accept_state(prefix(2), kMine, true, 50 * kMs));
  // past the silence: a restarted server (a new participant) is the server now
  EXPECT_FALSE(b.accept_state(prefix(2), 0, false, 150 * kMs));  // no grant yet
  EXPECT_TRUE(b.accept_state(prefix(2), kMine, true, 160 * kMs));
  EXPECT_EQ(b.rebinds(), 1u);
  EXPECT_TRUE(b.accept(ServerBinding::kStats, prefix(2)));
  EXPECT_FALSE(b.accept(ServerBinding::kStats, prefix(1)));
}

}  // namespace
}  // namespace teleop::master
