#pragma once
// Conversions between the controller's types and the DDS types of idl/Teleop.idl:
// SlaveCommand -> teleop::MasterCommand, teleop::SlaveState -> SlaveSample, and a
// teleop::MasterState filler. Header-only and allocation-free (fixed arrays only); include it
// where the generated types are wanted (the master node).
//
// Times: the IDL carries steady-clock nanoseconds; SlaveCommand/SlaveSample carry seconds.
// to_idl() takes the send stamp in ns; from_idl() converts the echoed command stamp with
// 1e-9 (absolute steady-clock seconds, the same clock the node uses for now_s if it uses
// teleop::now_ns() * 1e-9).
#include <cmath>
#include <cstdint>

#include "client/control/bilateral_controller.hpp"
#include "client/device/haptic_device.hpp"
#include "teleop/idl/Teleop.h"

namespace teleop::master {

namespace detail {
inline void put3(std::array<double, 3>& out, const Eigen::Vector3d& v) {
  out[0] = v.x();
  out[1] = v.y();
  out[2] = v.z();
}
inline Eigen::Vector3d get3(const std::array<double, 3>& a) {
  return Eigen::Vector3d(a[0], a[1], a[2]);
}
inline void put_q(std::array<double, 4>& out, const Eigen::Quaterniond& q) {
  out[0] = q.w();
  out[1] = q.x();
  out[2] = q.y();
  out[3] = q.z();
}
inline Eigen::Quaterniond get_q(const std::array<double, 4>& a) {
  Eigen::Quaterniond q(a[0], a[1], a[2], a[3]);
  if (q.norm() < 1e-9) return Eigen::Quaterniond::Identity();
  q.normalize();
  return q;
}
}  // namespace detail

/// SlaveCommand -> teleop::MasterCommand; `send_time_ns` is the master's steady clock [ns].
inline void to_idl(const SlaveCommand& c, std::int64_t send_time_ns, teleop::MasterCommand& m) {
  m.seq(c.seq);
  m.send_time_ns(send_time_ns);
  detail::put3(m.position_m(), c.position_m);
  detail::put_q(m.orientation_wxyz(), c.orientation);
  detail::put3(m.linear_velocity_mps(), c.velocity_mps);
  detail::put3(m.angular_velocity_radps(), c.angular_velocity_radps);
  m.scheme(static_cast<std::uint8_t>(c.scheme));
  detail::put3(m.master_force_n(), c.master_force_n);
  detail::put3(m.wave_u(), c.wave_u);
  m.position_gain_n_per_m(c.position_gain_n_per_m);
  m.enabled(c.enabled);
  m.passivity_session(c.passivity_session);
  m.wave_impedance_ns_per_m(c.wave_impedance_ns_per_m);
  m.wave_matched(c.wave_matched);
  detail::put3(m.wave_u_integral(), c.wave_u_integral);
  detail::put3(m.wave_u_energy_j(), c.wave_u_energy_j);
  m.tdpa_energy_in_j(c.tdpa_energy_in_j);
}

/// teleop::SlaveState -> SlaveSample (valid = true). Non-finite fields make it invalid: the
/// node should then drop it (and count a fault) rather than hand it to the channel.
inline SlaveSample from_idl(const teleop::SlaveState& m) {
  SlaveSample s;
  s.seq = m.seq();
  s.command_seq = m.command_seq();
  s.command_send_time_s = static_cast<double>(m.command_send_time_ns()) * 1e-9;
  s.sim_time_s = m.sim_time_s();
  s.position_m = detail::get3(m.tip_position_m());
  s.orientation = detail::get_q(m.tip_orientation_wxyz());
  s.velocity_mps = detail::get3(m.tip_linear_velocity_mps());
  s.contact_force_n = detail::get3(m.contact_force_n());
  s.wave_v = detail::get3(m.wave_v());
  s.penetration_m = m.penetration_m();
  s.deformation_m = m.deformation_m();
  s.in_contact = m.in_contact();
  s.passivity_session = m.passivity_session();
  s.wave_v_integral = detail::get3(m.wave_v_integral());
  s.wave_v_energy_j = detail::get3(m.wave_v_energy_j());
  s.tdpa_energy_in_j = m.tdpa_energy_in_j();
  s.tdpa_energy_out_j = m.tdpa_energy_out_j();
  s.passivity_dissipated_j = m.passivity_dissipated_j();
  s.valid = s.position_m.allFinite() && s.velocity_mps.allFinite() &&
            s.contact_force_n.allFinite() && std::isfinite(s.penetration_m) &&
            std::isfinite(s.deformation_m) && s.wave_v.allFinite() &&
            s.wave_v_integral.allFinite() && s.wave_v_energy_j.allFinite() &&
            std::isfinite(s.tdpa_energy_in_j) && std::isfinite(s.tdpa_energy_out_j) &&
            std::isfinite(s.passivity_dissipated_j);
  return s;
}

/// Fills the teleop::MasterState fields this library knows (the node adds seq, time, rtt).
inline void fill_master_state(const DeviceReading& r, const Eigen::Vector3d& rendered_force_n,
                              const Eigen::Vector3d& environment_force_n, double position_error_m,
                              double passivity_energy_j, SchemeId scheme, bool link_ok,
                              teleop::MasterState& m) {
  detail::put3(m.device_position_m(), r.position_m);
  detail::put_q(m.device_orientation_wxyz(), r.orientation);
  detail::put3(m.device_velocity_mps(), r.linear_velocity_mps);
  detail::put3(m.rendered_force_n(), rendered_force_n);
  detail::put3(m.environment_force_n(), environment_force_n);
  m.position_error_m(position_error_m);
  m.passivity_energy_j(passivity_energy_j);
  m.mode(static_cast<std::uint8_t>(scheme));
  m.link_ok(link_ok);
}

}  // namespace teleop::master
