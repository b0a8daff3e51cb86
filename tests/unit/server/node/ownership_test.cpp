// Ownership of the slave (server/node/ownership.hpp) and the command edge that applies it
// (command_gate.hpp): one owner at a time, refusals counted and reported once per writer, an
// explicit release, a takeover only after the owner's watchdog, malformed commands neither take
// nor keep the slave, and a new owner's sequence numbering starts afresh.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "server/node/command_gate.hpp"
#include "server/node/ownership.hpp"
#include "tests/support/alloc_counter.hpp"

namespace teleop::server {
namespace {

WriterId writer(std::uint8_t k) {
  WriterId w;
  w.bytes.fill(k);
  return w;
}

constexpr std::int64_t kMs = 1'000'000;

TEST(Ownership, FirstWriterOwnsOthersAreRefusedAndReportedOnce) {
  Ownership o(500 * kMs);
  EXPECT_EQ(o.owner_session(0), 0u);
  EXPECT_EQ(o.admit(writer(1), 0xa, "A", 1, false, 0), Admit::kAcquired);
  EXPECT_TRUE(o.notable());
  EXPECT_NE(std::string(o.message()).find("'A' (session 0x0000000a) owns the slave"),
            std::string::npos)
      << o.message();
  EXPECT_EQ(o.admit(writer(1), 0xa, "A", 2, false, 1 * kMs), Admit::kOwner);
  EXPECT_FALSE(o.notable());
  EXPECT_EQ(o.admit(writer(2), 0xb, "B", 1, false, 2 * kMs), Admit::kRefused);
  EXPECT_TRUE(o.notable());
  EXPECT_NE(std::string(o.message())
                .find("refused commands from master 'B' (session 0x0000000b): "
                      "the slave is owned by 'A' (session 0x0000000a)"),
            std::string::npos)
      << o.message();
  for (int k = 0; k < 10; ++k) {
    EXPECT_EQ(o.admit(writer(2), 0xb, "B", 2 + k, false, 3 * kMs), Admit::kRefused);
    EXPECT_FALSE(o.notable());  // once per writer
  }
  EXPECT_EQ(o.refused(), 11u);
  EXPECT_EQ(o.owner_session(3 * kMs), 0xau);
  EXPECT_EQ(o.owner_first_seq(), 1u);
  EXPECT_EQ(o.owner_received(), 2u);
  EXPECT_EQ(o.changes(), 1u);
}

TEST(Ownership, ReleaseFreesTheSlaveForTheNextWriter) {
  Ownership o(500 * kMs);
  o.admit(writer(1), 0xa, "A", 1, false, 0);
  EXPECT_EQ(o.admit(writer(2), 0xb, "B", 1, true, 1 * kMs), Admit::kIgnored);  // not its to give
  EXPECT_EQ(o.admit(writer(1), 0xa, "A", 2, true, 2 * kMs), Admit::kReleased);
  EXPECT_NE(std::string(o.message()).find("released the slave after 1 commands"), std::string::npos)
      << o.message();
  EXPECT_EQ(o.owner_session(2 * kMs), 0u);
  EXPECT_EQ(o.session(), 0xau);  // the last owner, for its final counts
  EXPECT_EQ(o.admit(writer(2), 0xb, "B", 7, false, 3 * kMs), Admit::kAcquired);
  EXPECT_EQ(o.owner_first_seq(), 7u);
  EXPECT_EQ(o.owner_received(), 1u);
  EXPECT_EQ(o.changes(), 2u);
}

TEST(Ownership, ASilentOwnerIsTakenOverOnlyAfterTheWatchdog) {
  Ownership o(500 * kMs);
  o.admit(writer(1), 0xa, "A", 1, false, 0);
  EXPECT_EQ(o.admit(writer(2), 0xb, "B", 1, false, 499 * kMs), Admit::kRefused);
  EXPECT_EQ(o.owner_session(500 * kMs), 0xau);
  EXPECT_EQ(o.owner_session(501 * kMs), 0u);  // silent past the watchdog: free to take
  EXPECT_EQ(o.admit(writer(2), 0xb, "B", 2, false, 501 * kMs), Admit::kTakenOver);
  EXPECT_NE(std::string(o.message())
                .find("took the slave over from 'A' (session 0x0000000a), "
                      "silent for 501 ms"),
            std::string::npos)
      << o.message();
  // the old owner comes back: it is refused now, and told once
  EXPECT_EQ(o.admit(writer(1), 0xa, "A", 2, false, 600 * kMs), Admit::kRefused);
  EXPECT_TRUE(o.notable());
  // a silent owner no one else wants keeps the slave
  Ownership p(500 * kMs);
  p.admit(writer(1), 0xa, "A", 1, false, 0);
  EXPECT_EQ(p.admit(writer(1), 0xa, "A", 2, false, 5000 * kMs), Admit::kOwner);
}

// Each notable decision names its masters in fields (what a master matches on, never the text):
// the one it is about, and the other one of a takeover or a refusal.
TEST(Ownership, EachDecisionNamesTheSessionsItIsAbout) {
  Ownership o(500 * kMs);
  o.admit(writer(1), 0xa, "A", 1, false, 0);
  EXPECT_EQ(o.tags().session, 0xau);
  EXPECT_EQ(o.tags().other_session, 0u);
  o.admit(writer(1), 0xa, "A", 2, false, 1 * kMs);  // not notable: no one named
  EXPECT_FALSE(o.notable());
  EXPECT_EQ(o.tags().session, 0u);
  o.admit(writer(2), 0xb, "B", 1, false, 2 * kMs);  // refused: B, held by A
  EXPECT_EQ(o.tags().session, 0xbu);
  EXPECT_EQ(o.tags().other_session, 0xau);
  o.admit(writer(2), 0xb, "B", 2, false, 600 * kMs);  // A silent: B takes over from A
  EXPECT_EQ(o.tags().session, 0xbu);
  EXPECT_EQ(o.tags().other_session, 0xau);
  o.admit(writer(2), 0xb, "B", 3, true, 601 * kMs);  // B releases
  EXPECT_EQ(o.tags().session, 0xbu);
  EXPECT_EQ(o.tags().other_session, 0u);
  EXPECT_EQ(o.tags().subject, sim::EventSubject::kNone);
}

MasterCommand command(std::uint64_t seq, std::uint32_t session) {
  MasterCommand c;
  c.seq(seq);
  c.position_m({0.5, 0.0, 0.5});
  c.orientation_wxyz({1.0, 0.0, 0.0, 0.0});
  c.enabled(true);
  c.master_session(session);
  c.master_name("m");
  return c;
}

TEST(CommandGate, MalformedCommandsNeitherTakeNorKeepTheSlave) {
  CommandGate gate(Eigen::Vector3d(-2, -2, -2), Eigen::Vector3d(2, 2, 2), 500 * kMs);
  MasterCommand nan = command(1, 0xc);
  nan.position_m()[0] = std::nan("");
  EXPECT_FALSE(gate.pass(nan, writer(3), 0));
  EXPECT_FALSE(gate.ownership().owned());  // a NaN flood cannot take a free slave
  EXPECT_TRUE(gate.pass(command(1, 0xa), writer(1), 1 * kMs));
  for (int k = 0; k < 100; ++k) EXPECT_FALSE(gate.pass(nan, writer(3), 2 * kMs));
  EXPECT_EQ(gate.counts().rejected_nan, 101u);
  EXPECT_EQ(gate.counts().refused_owner, 0u);  // rejected for what they are, not who sent them
  // the owner's numbering is its own: an interleaved writer does not reset it
  EXPECT_FALSE(gate.pass(command(50, 0xb), writer(2), 3 * kMs));
  EXPECT_TRUE(gate.pass(command(2, 0xa), writer(1), 4 * kMs));
  EXPECT_FALSE(gate.pass(command(2, 0xa), writer(1), 5 * kMs));  // repeated seq: stale
  EXPECT_EQ(gate.counts().rejected_stale, 1u);
  EXPECT_EQ(gate.counts().refused_owner, 1u);
  EXPECT_EQ(gate.counts().accepted, 2u);
}

TEST(CommandGate, ANewOwnerStartsItsOwnNumberingAndNothingAllocates) {
  CommandGate gate(Eigen::Vector3d(-2, -2, -2), Eigen::Vector3d(2, 2, 2), 500 * kMs);
  MasterCommand a = command(9000, 0xa), b = command(1, 0xb), rel = command(9001, 0xa);
  rel.release(true);
  teleop::test::NoAllocScope scope;
  EXPECT_TRUE(gate.pass(a, writer(1), 0));
  EXPECT_FALSE(gate.pass(rel, writer(1), 1 * kMs));
  EXPECT_EQ(gate.admit(), Admit::kReleased);
  EXPECT_TRUE(gate.pass(b, writer(2), 2 * kMs));  // seq 1 after 9000: a new owner, not stale
  EXPECT_EQ(gate.admit(), Admit::kAcquired);
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(gate.counts().releases, 1u);
}

}  // namespace
}  // namespace teleop::server
