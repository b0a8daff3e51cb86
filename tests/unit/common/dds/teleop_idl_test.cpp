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

TEST(TeleopIdl, ASampleWrittenAsSlaveStateReadsBackTheSame) {
  SlaveSample s;
  s.seq = 9;
  s.command_seq = 41;
  s.command_send_time_s = 2.5;
  s.sim_time_s = 1.25;
  s.position_m = Eigen::Vector3d(0.1, -0.2, 0.55);
  s.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY()));
  s.velocity_mps = Eigen::Vector3d(0.01, 0.02, -0.03);
  s.contact_force_n = Eigen::Vector3d(0.5, -0.25, 3.0);
  s.penetration_m = 0.002;
  s.deformation_m = 0.004;
  s.in_contact = true;
  s.passivity_session = 77;
  s.wave.v = Eigen::Vector3d(1.0, 2.0, 3.0);
  s.wave.v_integral = Eigen::Vector3d(0.1, 0.2, 0.3);
  s.wave.v_energy_j = Eigen::Vector3d(0.01, 0.02, 0.03);
  s.tdpa.energy_in_j = 0.5;
  s.tdpa.energy_out_j = 0.25;
  s.passivity_dissipated_j = 0.125;
  s.model.valid = true;
  s.model.touched = true;
  s.model.object_id = 3;
  s.model.normal = Eigen::Vector3d(0.0, 0.0, 1.0);
  s.model.offset_m = 0.5;
  s.model.stiffness_n_per_m = 900.0;
  s.model.damping_ns_per_m = 4.0;
  s.valid = true;
  teleop::SlaveState st;
  to_idl(s, 2500000000LL, st);
  const SlaveSample r = from_idl(st);
  EXPECT_EQ(r.seq, s.seq);
  EXPECT_EQ(r.command_seq, s.command_seq);
  EXPECT_EQ(r.command_send_time_s, s.command_send_time_s);
  EXPECT_EQ(r.sim_time_s, s.sim_time_s);
  EXPECT_EQ(r.position_m, s.position_m);
  EXPECT_NEAR(r.orientation.angularDistance(s.orientation), 0.0, 1e-12);
  EXPECT_EQ(r.velocity_mps, s.velocity_mps);
  EXPECT_EQ(r.contact_force_n, s.contact_force_n);
  EXPECT_EQ(r.penetration_m, s.penetration_m);
  EXPECT_EQ(r.deformation_m, s.deformation_m);
  EXPECT_EQ(r.in_contact, s.in_contact);
  EXPECT_EQ(r.passivity_session, s.passivity_session);
  EXPECT_EQ(r.wave.v, s.wave.v);
  EXPECT_EQ(r.wave.v_integral, s.wave.v_integral);
  EXPECT_EQ(r.wave.v_energy_j, s.wave.v_energy_j);
  EXPECT_EQ(r.tdpa.energy_in_j, s.tdpa.energy_in_j);
  EXPECT_EQ(r.tdpa.energy_out_j, s.tdpa.energy_out_j);
  EXPECT_EQ(r.passivity_dissipated_j, s.passivity_dissipated_j);
  EXPECT_EQ(r.model.valid, s.model.valid);
  EXPECT_EQ(r.model.touched, s.model.touched);
  EXPECT_EQ(r.model.object_id, s.model.object_id);
  EXPECT_EQ(r.model.normal, s.model.normal);
  EXPECT_EQ(r.model.offset_m, s.model.offset_m);
  EXPECT_EQ(r.model.stiffness_n_per_m, s.model.stiffness_n_per_m);
  EXPECT_EQ(r.model.damping_ns_per_m, s.model.damping_ns_per_m);
  EXPECT_TRUE(r.valid);
}

}  // namespace
