// How the master reacts to ownership (client/node/ownership_watch.hpp): another owner within the
// grace is not yet a refusal; a refusal without a wait gives up at once, one with a wait gives up
// when the wait is over, and getting the slave meanwhile ends the wait.
#include "client/node/ownership_watch.hpp"

#include <gtest/gtest.h>

namespace teleop::master {
namespace {

using Owner = DdsSlaveLink::Owner;
using Change = OwnershipWatch::Change;

constexpr double kT0 = 50.0;    // the loop's start [s]
constexpr double kGrace = 0.5;  // [s]

TEST(OwnershipWatch, AnotherOwnerWithinTheGraceIsNotARefusalAfterItOneIsAndEndsTheSession) {
  OwnershipWatch w(kT0, kGrace, 0.0);
  EXPECT_EQ(w.update(Owner::kUnknown, kT0 + 0.1), Change::kNone);
  EXPECT_EQ(w.update(Owner::kOther, kT0 + 0.4), Change::kNone);
  EXPECT_FALSE(w.refused());
  EXPECT_EQ(w.update(Owner::kOther, kT0 + 0.6), Change::kRefused);
  EXPECT_TRUE(w.refused());
  EXPECT_TRUE(w.give_up()) << "no wait: the session ends";
  EXPECT_TRUE(w.refused_first());
  EXPECT_EQ(w.update(Owner::kOther, kT0 + 0.7), Change::kNone) << "one refusal, one event";
  EXPECT_NEAR(w.waited_s(kT0 + 0.8), 0.2, 1e-9);
}

TEST(OwnershipWatch, AMasterThatOwnedTheSlaveIsRefusedAtOnceWhenItIsTakenAway) {
  OwnershipWatch w(kT0, kGrace, 0.0);
  EXPECT_EQ(w.update(Owner::kMine, kT0 + 0.1), Change::kNone);
  EXPECT_EQ(w.update(Owner::kOther, kT0 + 0.2), Change::kRefused) << "the grace is over once owned";
  EXPECT_FALSE(w.refused_first());
  EXPECT_TRUE(w.give_up());
}

TEST(OwnershipWatch, AWaitingMasterGetsTheSlaveAndReHomesOrGivesUpWhenTheWaitIsOver) {
  OwnershipWatch w(kT0, kGrace, 2.0);
  ASSERT_EQ(w.update(Owner::kOther, kT0 + 1.0), Change::kRefused);
  EXPECT_FALSE(w.give_up()) << "it waits";
  EXPECT_EQ(w.update(Owner::kOther, kT0 + 3.0), Change::kNone) << "2 s: not over yet";
  EXPECT_FALSE(w.give_up());
  EXPECT_EQ(w.update(Owner::kMine, kT0 + 2.5 + 1.0), Change::kGotSlave);
  EXPECT_FALSE(w.refused());
  EXPECT_NEAR(w.last_wait_s(), 2.5, 1e-9);
  EXPECT_EQ(w.update(Owner::kMine, kT0 + 4.0), Change::kNone);
  // taken away again: a second wait, which runs out
  ASSERT_EQ(w.update(Owner::kOther, kT0 + 5.0), Change::kRefused);
  EXPECT_FALSE(w.refused_first()) << "it owned the slave before this refusal";
  EXPECT_EQ(w.update(Owner::kOther, kT0 + 7.0), Change::kNone);
  EXPECT_FALSE(w.give_up());
  EXPECT_EQ(w.update(Owner::kOther, kT0 + 7.001), Change::kNone);
  EXPECT_TRUE(w.give_up());
  EXPECT_NEAR(w.waited_s(kT0 + 8.0), 2.5 + 3.0, 1e-9) << "both waits, the running one to the end";
}

}  // namespace
}  // namespace teleop::master
