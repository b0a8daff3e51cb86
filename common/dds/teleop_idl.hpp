#pragma once
// Conversions between the SI types of the bilateral loop (common/control/bilateral_types.hpp)
// and the DDS types of idl/Teleop.idl, for both sides: the master writes SlaveCommand as
// teleop::MasterCommand and reads teleop::SlaveState as SlaveSample; the server reads
// teleop::MasterCommand as SlaveCommand. Header-only and allocation-free (fixed arrays only).
//
// Times: the IDL carries steady-clock nanoseconds; SlaveCommand/SlaveSample carry seconds.
// to_idl() takes the send stamp in ns; from_idl() converts stamps with 1e-9 (absolute
// steady-clock seconds, the clock of teleop::now_ns()).
#include <cmath>
#include <cstdint>

#include "common/control/bilateral_types.hpp"
#include "teleop/idl/Teleop.h"

namespace teleop {

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
  m.position_gain_n_per_m(c.position_gain_n_per_m);
  m.enabled(c.enabled);
  m.release(c.release);
  m.passivity_session(c.passivity_session);
  for_each_port([&m](const auto& p) { to_wire(p, m); }, c);
}

/// A slave's local contact model into SlaveState (model-mediated scheme).
inline void to_idl(const mmt::LocalModel& l, teleop::SlaveState& m) {
  m.model_valid(l.valid);
  m.model_touched(l.touched);
  m.model_object(l.object_id);
  detail::put3(m.model_normal(), l.normal);
  m.model_offset_m(l.offset_m);
  m.model_stiffness_n_per_m(l.stiffness_n_per_m);
  m.model_damping_ns_per_m(l.damping_ns_per_m);
}

/// SlaveSample -> the fields of teleop::SlaveState the master reads back with from_idl (its
/// inverse); `command_send_time_ns` is the echoed command's stamp as it arrived [ns]. The fields
/// SlaveSample does not hold (joints, server clock, ownership, ...) are the caller's.
inline void to_idl(const SlaveSample& s, std::int64_t command_send_time_ns, teleop::SlaveState& m) {
  m.seq(s.seq);
  m.command_seq(s.command_seq);
  m.command_send_time_ns(command_send_time_ns);
  m.sim_time_s(s.sim_time_s);
  detail::put3(m.tip_position_m(), s.position_m);
  detail::put_q(m.tip_orientation_wxyz(), s.orientation);
  detail::put3(m.tip_linear_velocity_mps(), s.velocity_mps);
  detail::put3(m.contact_force_n(), s.contact_force_n);
  m.penetration_m(s.penetration_m);
  m.deformation_m(s.deformation_m);
  m.in_contact(s.in_contact);
  m.passivity_session(s.passivity_session);
  for_each_port([&m](const auto& p) { to_wire(p, m); }, s);
  m.passivity_dissipated_j(s.passivity_dissipated_j);
  to_idl(s.model, m);
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
  s.penetration_m = m.penetration_m();
  s.deformation_m = m.deformation_m();
  s.in_contact = m.in_contact();
  s.passivity_session = m.passivity_session();
  for_each_port([&m](auto& p) { from_wire(m, p); }, s);
  s.passivity_dissipated_j = m.passivity_dissipated_j();
  s.model.valid = m.model_valid();
  s.model.touched = m.model_touched();
  s.model.object_id = m.model_object();
  s.model.normal = detail::get3(m.model_normal());
  s.model.offset_m = m.model_offset_m();
  s.model.stiffness_n_per_m = m.model_stiffness_n_per_m();
  s.model.damping_ns_per_m = m.model_damping_ns_per_m();
  // a model that is not a surface (a normal not of unit length, non-finite or negative
  // figures) is dropped, not rendered
  if (s.model.valid &&
      !(std::abs(s.model.normal.norm() - 1.0) < 1e-3 && std::isfinite(s.model.offset_m) &&
        s.model.stiffness_n_per_m >= 0.0 && s.model.stiffness_n_per_m < 1e7 &&
        s.model.damping_ns_per_m >= 0.0 && s.model.damping_ns_per_m < 1e6)) {
    s.model.valid = false;
  }
  s.valid = s.position_m.allFinite() && s.velocity_mps.allFinite() &&
            s.contact_force_n.allFinite() && std::isfinite(s.penetration_m) &&
            std::isfinite(s.deformation_m) && ports_finite(s) &&
            std::isfinite(s.passivity_dissipated_j);
  return s;
}

/// teleop::MasterCommand -> SlaveCommand (the quaternion normalised; a near-zero one becomes
/// the identity). Validation (non-finite fields, workspace, staleness) is the caller's.
inline SlaveCommand from_idl(const teleop::MasterCommand& m) {
  SlaveCommand c;
  c.seq = m.seq();
  c.send_time_s = static_cast<double>(m.send_time_ns()) * 1e-9;
  c.position_m = detail::get3(m.position_m());
  c.orientation = detail::get_q(m.orientation_wxyz());
  c.velocity_mps = detail::get3(m.linear_velocity_mps());
  c.angular_velocity_radps = detail::get3(m.angular_velocity_radps());
  c.master_force_n = detail::get3(m.master_force_n());
  c.position_gain_n_per_m = m.position_gain_n_per_m();
  c.scheme = static_cast<SchemeId>(m.scheme());
  c.enabled = m.enabled();
  c.release = m.release();
  c.passivity_session = m.passivity_session();
  for_each_port([&m](auto& p) { from_wire(m, p); }, c);
  return c;
}

}  // namespace teleop
