// The press scenario (client/analysis/press_scenario.hpp) takes its gain axis and its theory
// from the scheme's traits, and refuses an unknown scheme naming the allowed ones.
#include "client/analysis/press_scenario.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "client/control/scheme_traits.hpp"
#include "tests/support/config_error.hpp"

namespace teleop::master {
namespace {

/// The scenario of a scheme label (as the campaigns and the delay sweep name them).
PressScenario scenario(const std::string& label) {
  ControllerParams law;
  apply_scheme_variant(label, law);
  PressScenario s;
  s.scheme = law.scheme;
  s.tdpa_base = law.tdpa_base;
  return s;
}

TEST(PressScenario, TheGainAxisFollowsTheSchemesTraits) {
  for (const std::string& label : scheme_variant_labels()) {
    SCOPED_TRACE(label);
    PressScenario s = scenario(label);
    s.gain = 2.0;
    ControllerParams law;
    apply_scheme_variant(label, law);
    const bool position = scheme_traits(law).position_based;
    EXPECT_EQ(press_position_like(s), position);
    // a position-based law's gain is K_pm = K_ps, another's K_f
    const PressSetup setup = build_press_setup(s);
    EXPECT_EQ(setup.loop.controller.master_stiffness_n_per_m, position ? 2.0 : 0.0);
    EXPECT_EQ(setup.loop.controller.slave_stiffness_n_per_m, position ? 2.0 : 400.0);
    EXPECT_EQ(setup.loop.controller.force_gain, position ? 1.0 : 2.0);
    EXPECT_EQ(press_loop_model(s, setup).position_position, position);
  }
}

TEST(PressScenario, TheTheoryFollowsTheSchemesTraits) {
  std::size_t finite = 0;
  for (const std::string& label : scheme_variant_labels()) {
    SCOPED_TRACE(label);
    PressScenario s = scenario(label);
    s.one_way_delay_s = 0.05;
    ControllerParams law;
    apply_scheme_variant(label, law);
    const SchemeTraits t = scheme_traits(law);
    PressResult r;
    fill_analytic(s, build_press_setup(s), r);
    EXPECT_EQ(r.passive_scheme, t.passive_by_design);
    // without a linear model the margin is infinite; with one, the defaults give a finite one
    EXPECT_EQ(std::isinf(r.analytic_margin_s), !t.linear_loop_model) << r.analytic_margin_s;
    if (!t.linear_loop_model) {
      EXPECT_TRUE(r.analytic_stable);
    }
    finite += std::isfinite(r.analytic_margin_s);
  }
  // position-position, force-position and tdpa on either
  EXPECT_EQ(finite, 4u);
}

TEST(PressScenario, AnUnknownSchemeIsRefusedNamingTheAllowedOnes) {
  PressScenario s;
  s.scheme = "pp";
  const std::string allowed = "scheme 'pp' is unknown (allowed: position-position";
  EXPECT_NE(test::config_error_of([&] { press_position_like(s); }).find(allowed),
            std::string::npos);
  EXPECT_NE(test::config_error_of([&] { build_press_setup(s); }).find(allowed), std::string::npos);
  PressResult r;
  EXPECT_NE(test::config_error_of([&] { fill_analytic(s, PressSetup{}, r); }).find(allowed),
            std::string::npos);
}

}  // namespace
}  // namespace teleop::master
