// The in-process point slave runs the common tool law exactly.
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
#include "client/sim/slave_model.hpp"
#include "common/dds/teleop_idl.hpp"
#include "common/sim/tool.hpp"
#include "tests/support/alloc_counter.hpp"
#include "tests/support/master_helpers.hpp"

using namespace teleop::master;
using namespace teleop;
using teleop::config::ConfigError;
using teleop::test::scenario;

namespace {

TEST(PointSlave, AgreesWithTheServersToolSceneOnAPlane) {
  const teleop::test::WallOnBothSlaves wall;
  PointSlave mine(wall.point);
  const teleop::sim::ToolModel& tm = wall.tool;
  teleop::sim::ToolState ts;
  ts.position_m = Eigen::Vector3d(0, 0, 0.6);
  mine.reset(ts.position_m);
  for (int i = 0; i < 2000; ++i) {
    SlaveCommand c;
    c.position_m = Eigen::Vector3d(0.01 * std::sin(0.003 * i), 0.0, 0.6 - 1e-4 * i);
    c.velocity_mps = Eigen::Vector3d(0.0, 0.0, -0.1);
    c.seq = static_cast<std::uint64_t>(i);
    teleop::sim::ToolInput in;
    in.target_position_m = c.position_m;
    in.target_velocity_mps = c.velocity_mps;
    mine.step(c, 1e-3);
    teleop::sim::tool_step(tm, ts, in, 1e-3);
    ASSERT_NEAR((mine.sample().position_m - ts.position_m).norm(), 0.0, 1e-9) << i;
    ASSERT_NEAR((mine.sample().contact_force_n - ts.contact_force_n).norm(), 0.0, 1e-6) << i;
  }
  EXPECT_TRUE(mine.sample().in_contact);
}

}  // namespace
