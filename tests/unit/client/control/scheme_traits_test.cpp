// What each scheme tells the shared code (client/control/scheme_traits.hpp): every scheme and
// variant gives exactly the answers the shared code used to decide by the scheme's name, the
// labels keep their order, and an unknown scheme or label is refused naming the allowed ones.
#include "client/control/scheme_traits.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "client/control/bilateral_controller.hpp"
#include "client/control/tuning.hpp"
#include "tests/support/config_error.hpp"

namespace teleop::master {
namespace {

using test::config_error_of;

/// One label's expected scheme, base law and traits.
struct Expected {
  const char* label;
  const char* scheme;
  const char* tdpa_base;
  std::uint32_t tunable_gains;
  bool position_based, passive_by_design, linear_loop_model;
  double rate_hz, command_rate_hz;
};

constexpr std::uint32_t kKpm = kTuneMasterStiffness, kBm = kTuneMasterDamping, kKf = kTuneForceGain,
                        kKps = kTuneSlaveStiffness;

// the answers tuning.cpp, press_scenario.cpp, link_verdict.cpp, campaign.cpp and teleop_master
// gave by comparing names, in the registry's order
const std::vector<Expected> kExpected = {
    {"position-position", "position-position", "position-position", kKpm | kBm | kKps, true, false,
     true, 0.0, 0.0},
    {"force-position", "force-position", "position-position", kKf | kBm | kKps, false, false, true,
     0.0, 0.0},
    {"wave-variables", "wave-variables", "position-position", kBm, true, true, false, 0.0, 0.0},
    {"tdpa", "tdpa", "position-position", kKpm | kBm | kKps, true, true, true, 0.0, 0.0},
    {"tdpa-fp", "tdpa", "force-position", kKf | kBm | kKps, false, true, true, 0.0, 0.0},
    {"model-mediated", "model-mediated", "position-position", kBm | kKps, false, true, false,
     4000.0, 1000.0},
};

TEST(SchemeTraits, EverySchemeAndVariantGivesTheAnswersTheSharedCodeGaveByName) {
  std::vector<std::string> labels;
  for (const Expected& e : kExpected) labels.emplace_back(e.label);
  // a new scheme or variant needs its row above
  ASSERT_EQ(scheme_variant_labels(), labels);
  for (const Expected& e : kExpected) {
    SCOPED_TRACE(e.label);
    ControllerParams p;
    apply_scheme_variant(e.label, p);
    EXPECT_EQ(p.scheme, e.scheme);
    EXPECT_EQ(p.tdpa_base, e.tdpa_base);
    const SchemeTraits t = scheme_traits(p);
    EXPECT_EQ(t.tunable_gains, e.tunable_gains);
    EXPECT_EQ(t.position_based, e.position_based);
    EXPECT_EQ(t.passive_by_design, e.passive_by_design);
    EXPECT_EQ(t.linear_loop_model, e.linear_loop_model);
    EXPECT_EQ(t.default_rate_hz, e.rate_hz);
    EXPECT_EQ(t.default_command_rate_hz, e.command_rate_hz);
  }
  // every registered scheme is named by some label
  for (const std::string& name : controller_names()) {
    bool named = false;
    for (const Expected& e : kExpected) named = named || name == e.scheme;
    EXPECT_TRUE(named) << name;
  }
}

TEST(SchemeTraits, AVariantSetsItsOwnParametersOnly) {
  ControllerParams p;
  p.force_gain = 2.5;
  p.master_damping_ns_per_m = 7.0;
  apply_scheme_variant("tdpa-fp", p);
  EXPECT_EQ(p.scheme, "tdpa");
  EXPECT_EQ(p.tdpa_base, "force-position");
  EXPECT_EQ(p.force_gain, 2.5);
  EXPECT_EQ(p.master_damping_ns_per_m, 7.0);
  apply_scheme_variant("tdpa", p);
  EXPECT_EQ(p.tdpa_base, "position-position");
  // a scheme without variants sets its name and nothing else
  p.tdpa_base = "force-position";
  apply_scheme_variant("wave-variables", p);
  EXPECT_EQ(p.scheme, "wave-variables");
  EXPECT_EQ(p.tdpa_base, "force-position");
}

TEST(SchemeTraits, AnUnknownSchemeOrLabelIsRefusedNamingTheAllowedOnes) {
  EXPECT_EQ(config_error_of([] { scheme_traits("pp"); }),
            "controller: scheme 'pp' is unknown (allowed: position-position, force-position, "
            "wave-variables, tdpa, model-mediated)");
  ControllerParams p;
  EXPECT_EQ(config_error_of([&] { apply_scheme_variant("tdpa-pp", p); }),
            "controller: scheme 'tdpa-pp' is unknown (allowed: position-position, "
            "force-position, wave-variables, tdpa, tdpa-fp, model-mediated)");
  EXPECT_EQ(p.scheme, ControllerParams{}.scheme);
  // a variant's label is not a scheme's name
  EXPECT_NE(config_error_of([] { scheme_traits("tdpa-fp"); }), "");
}

}  // namespace
}  // namespace teleop::master
