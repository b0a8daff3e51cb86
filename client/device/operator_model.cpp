#include "client/device/operator_model.hpp"

#include <algorithm>
#include <cmath>

#include "common/config/config.hpp"

namespace teleop::master {

namespace {

constexpr double kPi = 3.14159265358979323846;

/// Minimum-jerk blend s(u) = 10u^3 - 15u^4 + 6u^5 and its derivative ds/du, u in [0, 1].
void min_jerk(double u, double& s, double& ds) {
  u = std::clamp(u, 0.0, 1.0);
  const double u2 = u * u;
  s = u2 * u * (10.0 - 15.0 * u + 6.0 * u2);
  ds = 30.0 * u2 * (1.0 - 2.0 * u + u2);
}

/// Moves through `n` waypoints: each leg is a dwell of `dwell` then a minimum-jerk move of
/// `move` seconds. Returns the leg index (n-1 when finished).
int waypoint_path(const Eigen::Vector3d* wp, int n, double move, double dwell, double t,
                  bool repeat, Eigen::Vector3d& p, Eigen::Vector3d& v) {
  const double leg = move + dwell;
  const double total = leg * (n - 1);
  if (repeat && total > 0.0 && t >= total) t = std::fmod(t, total);
  if (t < 0.0) t = 0.0;
  int i = static_cast<int>(std::floor(t / leg));
  if (i >= n - 1) {
    p = wp[n - 1];
    v.setZero();
    return n - 1;
  }
  const double tl = t - leg * i;
  if (tl < dwell) {
    p = wp[i];
    v.setZero();
    return i;
  }
  double s = 0.0, ds = 0.0;
  min_jerk((tl - dwell) / move, s, ds);
  p = wp[i] + s * (wp[i + 1] - wp[i]);
  v = (ds / move) * (wp[i + 1] - wp[i]);
  return i;
}

}  // namespace

ScriptKind parse_script_kind(const std::string& name) {
  if (name == "hold") return ScriptKind::kHold;
  if (name == "line") return ScriptKind::kLine;
  if (name == "circle") return ScriptKind::kCircle;
  if (name == "step") return ScriptKind::kStep;
  if (name == "press-slip") return ScriptKind::kPressSlip;
  throw config::ConfigError("operator script '" + name +
                            "' is unknown (allowed: hold, line, circle, step, press-slip)");
}

const char* script_kind_name(ScriptKind kind) {
  switch (kind) {
    case ScriptKind::kHold:
      return "hold";
    case ScriptKind::kLine:
      return "line";
    case ScriptKind::kCircle:
      return "circle";
    case ScriptKind::kStep:
      return "step";
    case ScriptKind::kPressSlip:
      return "press-slip";
  }
  return "?";
}

OperatorScript press_slip_script(const Eigen::Vector3d& top_m, double press_depth_m) {
  OperatorScript s;
  s.kind = ScriptKind::kPressSlip;
  s.sphere_top_m = top_m;
  s.press_depth_m = press_depth_m;
  s.start_m = top_m + Eigen::Vector3d(0.0, 0.0, s.approach_height_m);
  return s;
}

double script_duration_s(const OperatorScript& s) {
  switch (s.kind) {
    case ScriptKind::kLine:
      return 2.0 * (s.segment_s + s.dwell_s);
    case ScriptKind::kPressSlip:
      return 4.0 * (s.segment_s + s.dwell_s) + s.dwell_s;
    default:
      return 0.0;
  }
}

IntendedPose intended_pose(const OperatorScript& s, double t) {
  IntendedPose out;
  out.position_m = s.start_m;
  switch (s.kind) {
    case ScriptKind::kHold:
      break;
    case ScriptKind::kLine: {
      const Eigen::Vector3d wp[3] = {s.start_m, s.line_end_m, s.start_m};
      out.phase = waypoint_path(wp, 3, s.segment_s, s.dwell_s, t, s.repeat, out.position_m,
                                out.velocity_mps);
      break;
    }
    case ScriptKind::kCircle: {
      // starts at the centre + r u with zero phase; the centre is start - r u so that the
      // trajectory begins where the hand already is.
      const double w = 2.0 * kPi / s.circle_period_s;
      const double a = w * std::max(0.0, t);
      const Eigen::Vector3d centre = s.start_m - s.circle_radius_m * s.circle_u;
      out.position_m =
          centre + s.circle_radius_m * (std::cos(a) * s.circle_u + std::sin(a) * s.circle_v);
      out.velocity_mps =
          s.circle_radius_m * w * (-std::sin(a) * s.circle_u + std::cos(a) * s.circle_v);
      out.phase = static_cast<int>(std::floor(a / (2.0 * kPi)));
      break;
    }
    case ScriptKind::kStep:
      if (t >= s.step_time_s) {
        out.position_m = s.start_m + s.step_m;
        out.phase = 1;
      }
      break;
    case ScriptKind::kPressSlip: {
      const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
      const Eigen::Vector3d approach = s.sphere_top_m + s.approach_height_m * up;
      const Eigen::Vector3d press = s.sphere_top_m - s.press_depth_m * up;
      const Eigen::Vector3d slip = press + s.slip_m;
      const Eigen::Vector3d depart = s.sphere_top_m + s.slip_m + s.approach_height_m * up;
      // approach -> contact -> press -> slip -> depart
      const Eigen::Vector3d wp[5] = {approach, s.sphere_top_m, press, slip, depart};
      out.phase = waypoint_path(wp, 5, s.segment_s, s.dwell_s, t, s.repeat, out.position_m,
                                out.velocity_mps);
      break;
    }
  }
  if (s.tremor_amplitude_m > 0.0) {
    static constexpr double kFreqHz[3] = {4.1, 7.3, 10.7};
    for (int axis = 0; axis < 3; ++axis) {
      for (int k = 0; k < 3; ++k) {
        const double w = 2.0 * kPi * kFreqHz[k];
        const double phase = 1.3 * axis + 2.1 * k;
        out.position_m[axis] += s.tremor_amplitude_m * std::sin(w * t + phase);
        out.velocity_mps[axis] += s.tremor_amplitude_m * w * std::cos(w * t + phase);
      }
    }
  }
  return out;
}

}  // namespace teleop::master
