#include "server/node/command_validation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "client/node/rtt.hpp"

namespace teleop::server {
namespace {

const Eigen::Vector3d kMin(-1, -1, 0), kMax(1, 1, 1);

MasterCommand valid(std::uint64_t seq) {
  MasterCommand c;
  c.seq(seq);
  c.position_m() = {0.1, 0.2, 0.3};
  c.orientation_wxyz() = {1, 0, 0, 0};
  c.enabled(true);
  return c;
}

TEST(CommandValidation, AcceptsAValidCommand) {
  EXPECT_EQ(validate_command(valid(1), kMin, kMax, 0, false), CommandVerdict::kAccepted);
  EXPECT_EQ(validate_command(valid(5), kMin, kMax, 4, true), CommandVerdict::kAccepted);
}

TEST(CommandValidation, RejectsNanAndInfAnywhere) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  auto c = valid(1);
  c.position_m()[1] = nan;
  EXPECT_EQ(validate_command(c, kMin, kMax, 0, false), CommandVerdict::kNonFinite);
  c = valid(1);
  c.linear_velocity_mps()[2] = inf;
  EXPECT_EQ(validate_command(c, kMin, kMax, 0, false), CommandVerdict::kNonFinite);
  c = valid(1);
  c.orientation_wxyz()[0] = nan;
  EXPECT_EQ(validate_command(c, kMin, kMax, 0, false), CommandVerdict::kNonFinite);
  c = valid(1);
  c.master_force_n()[0] = -inf;
  EXPECT_EQ(validate_command(c, kMin, kMax, 0, false), CommandVerdict::kNonFinite);
  c = valid(1);
  c.position_gain_n_per_m(nan);
  EXPECT_EQ(validate_command(c, kMin, kMax, 0, false), CommandVerdict::kNonFinite);
}

TEST(CommandValidation, RejectsOutsideWorkspaceBadQuaternionBadGainAndStale) {
  auto c = valid(1);
  c.position_m()[2] = 1.5;
  EXPECT_EQ(validate_command(c, kMin, kMax, 0, false), CommandVerdict::kOutsideWorkspace);
  c = valid(1);
  c.orientation_wxyz() = {0, 0, 0, 0};
  EXPECT_EQ(validate_command(c, kMin, kMax, 0, false), CommandVerdict::kBadOrientation);
  c = valid(1);
  c.position_gain_n_per_m(-3);
  EXPECT_EQ(validate_command(c, kMin, kMax, 0, false), CommandVerdict::kBadGain);
  EXPECT_EQ(validate_command(valid(7), kMin, kMax, 7, true), CommandVerdict::kStale);
  EXPECT_EQ(validate_command(valid(3), kMin, kMax, 7, true), CommandVerdict::kStale);
}

TEST(CommandValidation, ConvertsToAWorldCommand) {
  auto c = valid(1);
  c.orientation_wxyz() = {2, 0, 0, 0};  // not unit: normalised
  c.enabled(false);
  const auto w = to_world_command(c);
  EXPECT_DOUBLE_EQ(w.orientation.norm(), 1.0);
  EXPECT_TRUE(w.hold);
  EXPECT_EQ(w.position_m, Eigen::Vector3d(0.1, 0.2, 0.3));
}

TEST(RttTracker, CountsEachCommandOnceAndIgnoresForeignEchoes) {
  teleop::master::RttTracker t(16);
  EXPECT_LT(t.on_echo(0, 0, 5'000'000, 10), 0.0);  // nothing applied yet
  EXPECT_NEAR(t.on_echo(3, 1'000'000, 1'500'000, 10), 0.5, 1e-12);
  EXPECT_LT(t.on_echo(3, 1'000'000, 2'500'000, 10), 0.0);   // repeat of seq 3
  EXPECT_LT(t.on_echo(2, 1'000'000, 2'500'000, 10), 0.0);   // older
  EXPECT_LT(t.on_echo(99, 1'000'000, 2'500'000, 10), 0.0);  // from an earlier session
  EXPECT_NEAR(t.on_echo(4, 2'000'000, 3'000'000, 10), 1.0, 1e-12);
  EXPECT_EQ(t.unique_echoes(), 2u);
}

}  // namespace
}  // namespace teleop::server
