// What a master takes from its server's events (client/node/server_word.hpp): by field only,
// the session's faults and K_ps clamp, and every ownership decision that names the master.
#include <gtest/gtest.h>

#include <string>

#include "client/node/server_word.hpp"

namespace teleop::master {
namespace {

constexpr std::uint32_t kMine = 0x1234u;

Event event(const char* source, std::uint8_t kind, const char* text, std::uint32_t session = 0,
            std::uint32_t other = 0, std::uint8_t subject = EVENT_SUBJECT_NONE) {
  Event e;
  e.source() = source;
  e.kind(kind);
  e.message() = text;
  e.session(session);
  e.other_session(other);
  e.subject(subject);
  return e;
}

TEST(ServerWord, FaultsAndClampsCountFromTheSessionsStartAndOnlyItsOwn) {
  ServerWord w(kMine);
  w.on_event(event("server", EVENT_FAULT, "old fault"), 10);  // the log's history
  w.on_event(event("server", EVENT_LIMIT, "old clamp", kMine, 0, EVENT_SUBJECT_POSITION_GAIN), 10);
  w.start_session(100);
  EXPECT_EQ(w.faults(), 0u);
  EXPECT_EQ(w.gain_clamp(), "");
  w.on_event(event("server", EVENT_FAULT, "fault"), 150);
  w.on_event(event("master", EVENT_FAULT, "a master's own"), 150);  // not the server's word
  EXPECT_EQ(w.faults(), 1u);
  // another master's clamp, a limit that is not a clamp, a clamp that names no session
  w.on_event(event("server", EVENT_LIMIT, "theirs", 0x99u, 0, EVENT_SUBJECT_POSITION_GAIN), 160);
  w.on_event(event("server", EVENT_LIMIT, "joint limit position_gain_n_per_m", kMine), 160);
  w.on_event(event("server", EVENT_LIMIT, "none", 0, 0, EVENT_SUBJECT_POSITION_GAIN), 160);
  EXPECT_EQ(w.gain_clamp(), "");
  w.on_event(event("server", EVENT_LIMIT, "mine", kMine, 0, EVENT_SUBJECT_POSITION_GAIN), 170);
  EXPECT_EQ(w.gain_clamp(), "mine");
}

TEST(ServerWord, OwnershipDecisionsThatNameThisMasterEitherWay) {
  ServerWord w(kMine);
  // the text names the master's session in hex, the fields do not: not about it
  w.on_event(event("server", EVENT_OWNERSHIP, "master 'x' (session 0x00001234) owns", 0x5u), 1);
  EXPECT_EQ(w.ownership(), "");
  w.on_event(event("server", EVENT_OWNERSHIP, "owns", kMine), 2);  // before the session too
  EXPECT_EQ(w.ownership(), "owns");
  w.on_event(event("server", EVENT_OWNERSHIP, "refused other", 0x5u, kMine), 3);
  EXPECT_EQ(w.ownership(), "refused other");
  w.on_event(event("server", EVENT_OWNERSHIP, "taken over", 0x5u, kMine), 4);
  EXPECT_EQ(w.ownership(), "taken over");
  w.on_event(event("master", EVENT_OWNERSHIP, "own word", kMine), 5);
  EXPECT_EQ(w.ownership(), "taken over");
}

}  // namespace
}  // namespace teleop::master
