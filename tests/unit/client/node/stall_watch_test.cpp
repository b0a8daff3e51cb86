// A stall of the master's loop from the clock (client/node/stall_watch.hpp): a cycle that begins
// kStallS or more after the previous one, counted with its gap; overruns below that are not.
#include "client/node/stall_watch.hpp"

#include <gtest/gtest.h>

namespace teleop::master {
namespace {

TEST(StallWatch, AGapOfAStallsLengthOrMoreIsAStallAndShorterOnesAreNot) {
  StallWatch w;
  EXPECT_EQ(w.cycle_began(100.0), 0.0) << "the first cycle has no previous one";
  EXPECT_EQ(w.cycle_began(100.001), 0.0);
  EXPECT_EQ(w.cycle_began(100.051), 0.0) << "a 50 ms overrun is not a stall";
  EXPECT_EQ(w.stalls(), 0u);
  EXPECT_EQ(w.longest_s(), 0.0);
  EXPECT_EQ(w.cycle_began(100.250), 0.0) << "199 ms is not a stall yet";
  EXPECT_NEAR(w.cycle_began(101.750), 1.5, 1e-9);
  EXPECT_EQ(w.cycle_began(101.751), 0.0);
  EXPECT_NEAR(w.cycle_began(102.051), 0.3, 1e-9);
  EXPECT_EQ(w.stalls(), 2u);
  EXPECT_NEAR(w.longest_s(), 1.5, 1e-9);
}

TEST(StallWatch, TheFirstCycleIsNeverAStallAndAGapOfExactlyTheBoundIsOne) {
  StallWatch w;
  EXPECT_EQ(w.cycle_began(0.0), 0.0) << "whatever the clock reads";
  EXPECT_EQ(w.cycle_began(0.2), StallWatch::kStallS);
  ASSERT_EQ(0.4 - 0.2, StallWatch::kStallS);  // a gap of exactly the bound in doubles
  EXPECT_EQ(w.cycle_began(0.4), StallWatch::kStallS);
  EXPECT_EQ(w.stalls(), 2u);
}

}  // namespace
}  // namespace teleop::master
