#include "server/node/command_validation.hpp"

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
      !finite(cmd.master_force_n()) || !finite(cmd.wave_u()) ||
      !std::isfinite(cmd.position_gain_n_per_m())) {
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

sim::WorldCommand to_world_command(const MasterCommand& cmd) {
  sim::WorldCommand w;
  const auto& p = cmd.position_m();
  const auto& q = cmd.orientation_wxyz();
  const auto& v = cmd.linear_velocity_mps();
  const auto& a = cmd.angular_velocity_radps();
  w.position_m = {p[0], p[1], p[2]};
  w.orientation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized();
  w.velocity_mps = {v[0], v[1], v[2]};
  w.angular_velocity_radps = {a[0], a[1], a[2]};
  w.kp_override_n_per_m = cmd.position_gain_n_per_m();
  w.hold = !cmd.enabled();
  return w;
}

}  // namespace teleop::server
