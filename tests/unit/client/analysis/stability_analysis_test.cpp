// The linear stability analysis of the press task.
#include <gtest/gtest.h>

#include "tests/support/config_error.hpp"

#include <cmath>
#include <functional>

#include "client/analysis/press_scenario.hpp"
#include "client/analysis/stability_analysis.hpp"
#include "client/control/bilateral_controller.hpp"
#include "client/control/safety.hpp"
#include "client/device/simulated_device.hpp"
#include "client/sim/loopback_session.hpp"
#include "common/dds/teleop_idl.hpp"
#include "common/sim/tool.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/support/master_helpers.hpp"
#include "tests/support/press_world.hpp"

using namespace teleop::master;
using namespace teleop;

namespace {

TEST(StabilityAnalysis, MarginShrinksWithGainAndIsInfiniteForSmallLoopGain) {
  LoopModel m;
  m.position_position = false;
  m.force_gain = 0.1;
  EXPECT_TRUE(std::isinf(delay_margin(m).one_way_s));
  m.force_gain = 1.0;
  const double a = delay_margin(m).one_way_s;
  m.force_gain = 2.0;
  const double b = delay_margin(m).one_way_s;
  EXPECT_TRUE(std::isfinite(a));
  EXPECT_LT(b, a);
  // at the margin the delayed loop gain is exactly -1
  m.force_gain = 1.0;
  const DelayMargin dm = delay_margin(m);
  const std::complex<double> l =
      loop_gain(m, dm.crossover_radps) *
      std::exp(std::complex<double>(0, -2.0 * dm.crossover_radps * dm.one_way_s));
  EXPECT_NEAR(l.real(), -1.0, 1e-6);
  EXPECT_NEAR(l.imag(), 0.0, 1e-6);
}

}  // namespace
