// Conversions between the control types and the IDL messages (common/dds/teleop_idl.hpp).
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

TEST(TeleopIdl, CommandAndStateRoundTripThroughTheDdsTypes) {
  SlaveCommand c;
  c.seq = 41;
  c.position_m = Eigen::Vector3d(0.1, 0.2, 0.3);
  c.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  c.velocity_mps = Eigen::Vector3d(1, 2, 3);
  c.scheme = SchemeId::kForcePosition;
  c.position_gain_n_per_m = 400;
  c.enabled = true;
  teleop::MasterCommand m;
  to_idl(c, 123456789, m);
  EXPECT_EQ(m.seq(), 41u);
  EXPECT_EQ(m.send_time_ns(), 123456789);
  EXPECT_EQ(m.position_m()[2], 0.3);
  EXPECT_NEAR(m.orientation_wxyz()[0], c.orientation.w(), 1e-15);
  EXPECT_EQ(m.scheme(), 1);
  EXPECT_TRUE(m.enabled());

  teleop::SlaveState st;
  st.seq(5);
  st.command_seq(41);
  st.command_send_time_ns(2500000000LL);
  st.tip_position_m({0.0, 0.0, 0.55});
  st.tip_orientation_wxyz({1.0, 0.0, 0.0, 0.0});
  st.contact_force_n({0.0, 0.0, 3.0});
  st.in_contact(true);
  SlaveSample s = from_idl(st);
  EXPECT_TRUE(s.valid);
  EXPECT_EQ(s.command_seq, 41u);
  EXPECT_DOUBLE_EQ(s.command_send_time_s, 2.5);
  EXPECT_EQ(s.contact_force_n.z(), 3.0);
  EXPECT_TRUE(s.in_contact);
  st.contact_force_n({std::nan(""), 0.0, 0.0});
  EXPECT_FALSE(from_idl(st).valid);
}

}  // namespace
