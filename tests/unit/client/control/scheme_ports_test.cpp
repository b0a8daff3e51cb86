// The schemes' port structs (common/control/schemes/*_port.hpp): every field crosses the wire
// unchanged through the one conversion per scheme, and the checks the server and the slave port
// run on them reach each scheme's functions through for_each_port().
#include <gtest/gtest.h>

#include <cmath>

#include "common/control/slave_port.hpp"
#include "common/dds/teleop_idl.hpp"

using namespace teleop;
namespace pv = teleop::passivity;
using Eigen::Vector3d;

namespace {

TEST(SchemePorts, EveryPortFieldCrossesTheWireUnchanged) {
  SlaveCommand c;
  c.wave.u = Vector3d(0.5, -1.5, 2.5);
  c.wave.impedance_ns_per_m = 7.25;
  c.wave.matched = false;
  c.wave.u_integral = Vector3d(1, 2, 3);
  c.wave.u_energy_j = Vector3d(4, 5, 6);
  c.tdpa.energy_in_j = 0.375;
  MasterCommand m;
  to_idl(c, 1, m);
  const SlaveCommand back = from_idl(m);
  EXPECT_EQ(back.wave.u, c.wave.u);
  EXPECT_EQ(back.wave.impedance_ns_per_m, 7.25);
  EXPECT_FALSE(back.wave.matched);
  EXPECT_EQ(back.wave.u_integral, c.wave.u_integral);
  EXPECT_EQ(back.wave.u_energy_j, c.wave.u_energy_j);
  EXPECT_EQ(back.tdpa.energy_in_j, 0.375);

  pv::SlavePortReport r;
  r.wave.v = Vector3d(-0.5, 0.25, 0.125);
  r.wave.v_integral = Vector3d(7, 8, 9);
  r.wave.v_energy_j = Vector3d(10, 11, 12);
  r.tdpa.energy_in_j = 1.5;
  r.tdpa.energy_out_j = 1.25;
  SlaveState st;
  st.tip_orientation_wxyz({1.0, 0.0, 0.0, 0.0});
  for_each_port([&st](const auto& p) { to_wire(p, st); }, r);
  const SlaveSample s = from_idl(st);
  EXPECT_TRUE(s.valid);
  EXPECT_EQ(s.wave.v, r.wave.v);
  EXPECT_EQ(s.wave.v_integral, r.wave.v_integral);
  EXPECT_EQ(s.wave.v_energy_j, r.wave.v_energy_j);
  EXPECT_EQ(s.tdpa.energy_in_j, 1.5);
  EXPECT_EQ(s.tdpa.energy_out_j, 1.25);
}

TEST(SchemePorts, TheChecksReachEachSchemesFields) {
  pv::SlavePortCommand ok;
  ok.scheme = pv::kSchemeWaveVariables;
  ok.wave.impedance_ns_per_m = 10.0;
  ok.wave.u_energy_j = Vector3d(0, 0, 0.5);
  ok.tdpa.energy_in_j = 0.5;
  EXPECT_EQ(pv::check_port_command(ok), pv::PortCommandCheck::kOk);

  pv::SlavePortCommand c = ok;
  c.wave.u.y() = std::nan("");
  EXPECT_EQ(pv::check_port_command(c), pv::PortCommandCheck::kNonFinite);
  c = ok;
  c.tdpa.energy_in_j = std::nan("");
  EXPECT_EQ(pv::check_port_command(c), pv::PortCommandCheck::kNonFinite);
  c = ok;
  c.wave.impedance_ns_per_m = 0.0;  // b applies to wave variables only
  EXPECT_EQ(pv::check_port_command(c), pv::PortCommandCheck::kBadImpedance);
  c.scheme = pv::kSchemeTimeDomainPassivity;
  EXPECT_EQ(pv::check_port_command(c), pv::PortCommandCheck::kOk);
  c = ok;
  c.tdpa.energy_in_j = -1e-9;
  EXPECT_EQ(pv::check_port_command(c), pv::PortCommandCheck::kNegativeEnergy);
  c = ok;
  c.wave.u_energy_j.x() = -1e-9;
  EXPECT_EQ(pv::check_port_command(c), pv::PortCommandCheck::kNegativeEnergy);

  pv::SlavePortCommand later = ok;
  EXPECT_FALSE(pv::energy_decreased(later, ok, 0.0));
  later.tdpa.energy_in_j = 0.5 - 1e-6;
  EXPECT_TRUE(pv::energy_decreased(later, ok, 0.0));
  EXPECT_FALSE(pv::energy_decreased(later, ok, 1e-5));
  later = ok;
  later.wave.u_energy_j.z() = 0.5 - 1e-6;
  EXPECT_TRUE(pv::energy_decreased(later, ok, 0.0));
  EXPECT_FALSE(pv::energy_decreased(later, ok, 1e-5));
}

}  // namespace
