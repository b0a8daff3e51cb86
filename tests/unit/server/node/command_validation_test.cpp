#include "server/node/command_validation.hpp"
#include "common/dds/teleop_idl.hpp"
#include "server/node/server_cycle.hpp"

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
  const auto w = sim::to_world_command(from_idl(c));
  EXPECT_DOUBLE_EQ(w.orientation.norm(), 1.0);
  EXPECT_TRUE(w.hold);
  EXPECT_EQ(w.position_m, Eigen::Vector3d(0.1, 0.2, 0.3));
}

MasterCommand wave(std::uint64_t seq, double energy_j) {
  auto c = valid(seq);
  c.scheme(SCHEME_WAVE_VARIABLES);
  c.passivity_session(5);
  c.wave_impedance_ns_per_m(10.0);
  c.wave_u_integral() = {0.0, 0.0, -0.01 * static_cast<double>(seq)};
  c.wave_u_energy_j() = {0.0, 0.0, energy_j};
  return c;
}

TEST(CommandValidation, RejectsUnusableWaveAndPassivityFields) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  PassivityHistory h;
  EXPECT_EQ(validate_passivity(wave(1, 0.1), h), CommandVerdict::kAccepted);
  EXPECT_EQ(validate_passivity(wave(2, 0.2), h), CommandVerdict::kAccepted);
  // a non-finite wave is non-finite, wherever it is
  auto c = wave(3, 0.3);
  c.wave_u_integral()[0] = nan;
  EXPECT_EQ(validate_command(c, kMin, kMax, 2, true), CommandVerdict::kNonFinite);
  c = wave(3, 0.3);
  c.tdpa_energy_in_j(std::numeric_limits<double>::infinity());
  EXPECT_EQ(validate_command(c, kMin, kMax, 2, true), CommandVerdict::kNonFinite);
  // b out of range, a negative energy, an energy that went back within the session
  c = wave(3, 0.3);
  c.wave_impedance_ns_per_m(0.0);
  EXPECT_EQ(validate_passivity(c, h), CommandVerdict::kBadPassivity);
  c = wave(3, 0.3);
  c.wave_impedance_ns_per_m(1e9);
  EXPECT_EQ(validate_passivity(c, h), CommandVerdict::kBadPassivity);
  c = wave(3, -0.3);
  EXPECT_EQ(validate_passivity(c, h), CommandVerdict::kBadPassivity);
  EXPECT_EQ(validate_passivity(wave(3, 0.15), h), CommandVerdict::kBadPassivity);  // stale
  auto tdpa = valid(4);
  tdpa.scheme(SCHEME_TIME_DOMAIN_PASSIVITY);
  tdpa.passivity_session(5);
  tdpa.tdpa_energy_in_j(-1.0);
  EXPECT_EQ(validate_passivity(tdpa, h), CommandVerdict::kBadPassivity);
  // a new session starts its energies from zero
  auto next = wave(4, 0.01);
  next.passivity_session(6);
  EXPECT_EQ(validate_passivity(next, h), CommandVerdict::kAccepted);
  // the other schemes do not use the fields
  auto pp = valid(5);
  pp.wave_impedance_ns_per_m(-4.0);
  EXPECT_EQ(validate_passivity(pp, h), CommandVerdict::kAccepted);
  EXPECT_STREQ(to_string(CommandVerdict::kBadPassivity), "wave / passivity fields out of range");
}

TEST(CommandValidation, ConvertsThePassivityFields) {
  const passivity::SlavePortCommand p = passivity::port_command(from_idl(wave(3, 0.5)));
  EXPECT_EQ(p.scheme, SCHEME_WAVE_VARIABLES);
  EXPECT_EQ(p.session, 5u);
  EXPECT_TRUE(p.enabled);
  EXPECT_EQ(p.wave.impedance_ns_per_m, 10.0);
  EXPECT_DOUBLE_EQ(p.wave.u_integral.z(), -0.03);
  EXPECT_EQ(p.wave.u_energy_j.z(), 0.5);
  EXPECT_EQ(p.position_m, Eigen::Vector3d(0.1, 0.2, 0.3));
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
