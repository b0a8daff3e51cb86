#include "server/node/command_validation.hpp"

#include "common/dds/teleop_idl.hpp"

#include <cmath>

namespace teleop::server {

const char* to_string(CommandVerdict v) {
  switch (v) {
    case CommandVerdict::kAccepted:
      return "accepted";
    case CommandVerdict::kNonFinite:
      return "non-finite value";
    case CommandVerdict::kBadOrientation:
      return "invalid orientation quaternion";
    case CommandVerdict::kOutsideWorkspace:
      return "position outside the workspace";
    case CommandVerdict::kBadGain:
      return "position gain out of range";
    case CommandVerdict::kStale:
      return "stale sequence number";
    case CommandVerdict::kBadPassivity:
      return "wave / passivity fields out of range";
  }
  return "?";
}

namespace {
template <std::size_t N>
bool finite(const std::array<double, N>& a) {
  for (double v : a) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}
}  // namespace

CommandVerdict validate_command(const MasterCommand& cmd, const Eigen::Vector3d& workspace_min_m,
                                const Eigen::Vector3d& workspace_max_m, std::uint64_t last_seq,
                                bool have_last) {
  if (!finite(cmd.position_m()) || !finite(cmd.orientation_wxyz()) ||
      !finite(cmd.linear_velocity_mps()) || !finite(cmd.angular_velocity_radps()) ||
      !finite(cmd.master_force_n()) || !std::isfinite(cmd.position_gain_n_per_m()) ||
      !ports_finite(from_idl(cmd))) {
    return CommandVerdict::kNonFinite;
  }
  auto norm3 = [](const std::array<double, 3>& a) {
    return std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);  // inf when it overflows
  };
  if (!(norm3(cmd.linear_velocity_mps()) <= kMaxCommandSpeedMps) ||
      !(norm3(cmd.angular_velocity_radps()) <= kMaxCommandAngularSpeedRadps) ||
      !(norm3(cmd.master_force_n()) <= kMaxCommandForceN)) {
    return CommandVerdict::kNonFinite;
  }
  const auto& q = cmd.orientation_wxyz();
  const double qn = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  if (qn < 0.5 || qn > 2.0) return CommandVerdict::kBadOrientation;
  for (int i = 0; i < 3; ++i) {
    const double p = cmd.position_m()[static_cast<std::size_t>(i)];
    if (p < workspace_min_m[i] || p > workspace_max_m[i]) return CommandVerdict::kOutsideWorkspace;
  }
  if (cmd.position_gain_n_per_m() < 0.0 || cmd.position_gain_n_per_m() > 1e6) {
    return CommandVerdict::kBadGain;
  }
  if (have_last && cmd.seq() <= last_seq) return CommandVerdict::kStale;
  return CommandVerdict::kAccepted;
}

CommandVerdict validate_passivity(const MasterCommand& cmd, PassivityHistory& history) {
  if (!passivity::SlavePassivityPort::handles(cmd.scheme())) return CommandVerdict::kAccepted;
  const passivity::SlavePortCommand p = passivity::port_command(from_idl(cmd));
  switch (passivity::check_port_command(p)) {
    case passivity::PortCommandCheck::kOk:
      break;
    case passivity::PortCommandCheck::kNonFinite:
      return CommandVerdict::kNonFinite;
    default:
      return CommandVerdict::kBadPassivity;
  }
  // cumulative energies never decrease within a session: an older value is stale or corrupt
  if (history.have && history.session == p.session &&
      passivity::energy_decreased(p, history.last, 0.0)) {
    return CommandVerdict::kBadPassivity;
  }
  history.have = true;
  history.session = p.session;
  history.last = p;
  return CommandVerdict::kAccepted;
}

}  // namespace teleop::server
