// teleop_experiment robot-reach --out DIR [--quick] [--no-chart] [--scene FILE]
//   [--stepper step|quick]
// The PUMA 560 slave tip follows a commanded path through the default scene: it descends to
// the floor and presses on it, lifts, turns its tool toward the side wall, presses on the wall
// and returns home. The world (arm and planes) is advanced by world_step, as the server
// advances its scene. Writes robot_reach.csv (time series), robot_reach_events.csv and
// robot_reach_summary.csv, then the chart robot_reach.png.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "common/config/config.hpp"
#include "common/util/csv.hpp"
#include "common/util/registry.hpp"
#include "server/robot/robot_sim.hpp"
#include "server/world/world.hpp"
#include "server/world/world_model.hpp"

namespace {

using teleop::sim::robot::ControlMode;
using teleop::sim::robot::RobotInput;
using teleop::sim::robot::RobotModel;
using teleop::sim::robot::RobotSim;

/// One waypoint of the commanded tip path.
struct Waypoint {
  Eigen::Vector3d p;     ///< tip centre [m]
  Eigen::Quaterniond R;  ///< tool orientation
  double move_s;         ///< time to reach it from the previous waypoint [s]
  double dwell_s;        ///< time spent at it [s]
  const char* label;
};

/// Minimum-jerk blend s(u), u in [0, 1], and its derivative ds/du.
void min_jerk(double u, double& s, double& ds) {
  u = std::clamp(u, 0.0, 1.0);
  s = u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
  ds = 30.0 * u * u * (1.0 - u) * (1.0 - u);
}

/// The commanded path through the default scene, from the arm's home pose (tip radius r [m]).
std::vector<Waypoint> reach_path(const RobotSim& sim, double r) {
  // tool pointing down, tilted 0.4 rad away from the robot (keeps the wrist off its singularity)
  const Eigen::Quaterniond down(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY()) *
                                Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()));
  // tool horizontal, pointing at the wall (+y)
  const Eigen::Quaterniond side(Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX()));
  const Eigen::Vector3d home = sim.state().tip_pose.translation();
  const Eigen::Quaterniond home_R(sim.state().tip_pose.linear());
  return {
      {home, home_R, 0.0, 0.3, "home"},
      {Eigen::Vector3d(0.45, 0.05, 0.25), down, 1.5, 0.3, "above floor"},
      {Eigen::Vector3d(0.45, 0.05, r + 0.002), down, 1.0, 0.2, "floor touch"},
      {Eigen::Vector3d(0.45, 0.05, r - 0.02), down, 0.8, 0.8, "floor press 2 cm"},
      {Eigen::Vector3d(0.45, 0.05, 0.25), down, 1.0, 0.2, "lift"},
      {Eigen::Vector3d(0.30, 0.35, 0.45), side, 1.5, 0.3, "face wall"},
      {Eigen::Vector3d(0.30, 0.6 - r - 0.002, 0.45), side, 1.0, 0.2, "wall touch"},
      {Eigen::Vector3d(0.30, 0.6 - r + 0.02, 0.45), side, 0.8, 0.8, "wall press 2 cm"},
      {Eigen::Vector3d(0.30, 0.35, 0.45), side, 1.0, 0.2, "back off"},
      {Eigen::Vector3d(0.45, 0.05, 0.45), down, 1.5, 0.2, "tool down"},
      {home, home_R, 1.0, 0.5, "home"},
  };
}

/// The target pose and twist at time tl [s] into the segment a -> b (move time move [s]):
/// minimum-jerk along the segment, then held at b.
void set_target(const Waypoint& a, const Waypoint& b, double move, double tl, RobotInput& in) {
  double s = 1.0, ds = 0.0;
  if (move > 0.0) min_jerk(tl / move, s, ds);
  in.target_position_m = a.p + s * (b.p - a.p);
  in.target_velocity_mps = move > 0.0 && tl < move ? Eigen::Vector3d((ds / move) * (b.p - a.p))
                                                   : Eigen::Vector3d::Zero();
  in.target_orientation = a.R.slerp(s, b.R);
  const Eigen::AngleAxisd dR(b.R * a.R.inverse());
  in.target_angular_velocity_radps = move > 0.0 && tl < move
                                         ? Eigen::Vector3d((ds / move) * dR.angle() * dR.axis())
                                         : Eigen::Vector3d::Zero();
}

/// The run's extremes, for the summary.
struct ReachStats {
  double max_free_error = 0.0, max_floor_force = 0.0, max_wall_force = 0.0;
  double max_floor_pen = 0.0, max_wall_pen = 0.0;
  int max_link_contacts = 0;
};

/// One row of robot_reach.csv: time t [s], segment w, target, tip, errors, contact, joints.
void write_row(teleop::CsvWriter& csv, double t, std::size_t w, const RobotInput& in,
               const teleop::sim::robot::RobotState& st, double err, double rot_err, double f) {
  const Eigen::Vector3d tip = st.tip_pose.translation();
  std::vector<double> row = {t,
                             static_cast<double>(w),
                             in.target_position_m.x(),
                             in.target_position_m.y(),
                             in.target_position_m.z(),
                             tip.x(),
                             tip.y(),
                             tip.z(),
                             err,
                             rot_err,
                             st.tip_contact_force_n.x(),
                             st.tip_contact_force_n.y(),
                             st.tip_contact_force_n.z(),
                             f,
                             st.tip_in_contact ? 1.0 : 0.0,
                             static_cast<double>(st.tip_contact_plane),
                             st.tip_penetration_m,
                             st.controller.sigma_min_m};
  for (int i = 0; i < 6; ++i) row.push_back(st.q(i));
  for (int i = 0; i < 6; ++i) row.push_back(st.tau(i));
  row.push_back(static_cast<double>(st.link_contacts));
  csv.row(row);
}

/// Records the state after a step of segment b (target in) into the extremes and the CSV row.
void record_step(const RobotSim& sim, const std::vector<teleop::sim::Plane>& planes,
                 const Waypoint& b, const RobotInput& in, double t, std::size_t w,
                 ReachStats& stats, teleop::CsvWriter& csv) {
  const auto& st = sim.state();
  const Eigen::Vector3d tip = st.tip_pose.translation();
  const double err = (tip - in.target_position_m).norm();
  const double rot_err =
      teleop::sim::robot::rotation_vector(in.target_orientation.toRotationMatrix() *
                                          st.tip_pose.linear().transpose())
          .norm();
  const double f = st.tip_contact_force_n.norm();
  const bool pressing = std::string(b.label).find("press") != std::string::npos ||
                        std::string(b.label).find("touch") != std::string::npos;
  if (!pressing && !st.tip_in_contact) stats.max_free_error = std::max(stats.max_free_error, err);
  if (st.tip_contact_plane == planes[0].id) {
    stats.max_floor_force = std::max(stats.max_floor_force, f);
    stats.max_floor_pen = std::max(stats.max_floor_pen, st.tip_penetration_m);
  }
  if (st.tip_contact_plane == planes[1].id) {
    stats.max_wall_force = std::max(stats.max_wall_force, f);
    stats.max_wall_pen = std::max(stats.max_wall_pen, st.tip_penetration_m);
  }
  stats.max_link_contacts = std::max(stats.max_link_contacts, st.link_contacts);
  write_row(csv, t, w, in, st, err, rot_err, f);
}

/// robot_reach_summary.csv and the printed summary.
void write_summary(const teleop::CommandArgs& args, const RobotModel& model,
                   const std::string& stepper, double t, const ReachStats& stats,
                   const RobotSim& sim) {
  teleop::CsvWriter sum((args.out_dir / "robot_reach_summary.csv").string(), {"metric", "value"});
  auto put = [&](const std::string& k, double v) {
    sum.row_text({k, teleop::format_number(v)});
    std::printf("  %-34s %.6g\n", k.c_str(), v);
  };
  std::printf("robot-reach (%s, %s):\n", model.name.c_str(),
              stepper == "quick" ? "dWorldQuickStep" : "dWorldStep");
  put("duration_s", t);
  put("max_free_tracking_error_m", stats.max_free_error);
  put("max_floor_force_n", stats.max_floor_force);
  put("max_floor_penetration_m", stats.max_floor_pen);
  put("max_wall_force_n", stats.max_wall_force);
  put("max_wall_penetration_m", stats.max_wall_pen);
  put("max_link_contacts", stats.max_link_contacts);
  put("faults", static_cast<double>(sim.state().faults));
  put("limit_events", static_cast<double>(sim.state().controller.limit_events));
  put("singular_events", static_cast<double>(sim.state().controller.singular_events));
  sum.flush();
}

/// The columns of robot_reach.csv (write_row).
std::vector<std::string> reach_columns() {
  return {"t_s",           "segment",       "target_x_m",  "target_y_m", "target_z_m",
          "tip_x_m",       "tip_y_m",       "tip_z_m",     "error_m",    "orientation_error_rad",
          "force_x_n",     "force_y_n",     "force_z_n",   "force_n",    "in_contact",
          "contact_plane", "penetration_m", "sigma_min_m", "q1_rad",     "q2_rad",
          "q3_rad",        "q4_rad",        "q5_rad",      "q6_rad",     "tau1_nm",
          "tau2_nm",       "tau3_nm",       "tau4_nm",     "tau5_nm",    "tau6_nm",
          "link_contacts"};
}

/// The step's events (plane contacts among them), one row each, the queue emptied.
void write_events(teleop::sim::EventQueue& events, teleop::CsvWriter& ev_csv) {
  teleop::sim::SimEvent e;
  while (events.pop(e)) {
    ev_csv.row_text({teleop::format_number(e.sim_time_s), std::to_string(static_cast<int>(e.kind)),
                     teleop::format_number(e.value), std::string("\"") + e.message + "\""});
  }
}

int run_robot_reach(const teleop::CommandArgs& args) {
  const std::string scene = args.option("--scene", teleop::sim::robot::default_robot_scene_path());
  const std::string stepper = args.option("--stepper", "step");
  if (stepper != "step" && stepper != "quick") {
    throw teleop::config::ConfigError("--stepper: value '" + stepper +
                                      "' is not one of: step, quick");
  }
  const RobotModel model = teleop::sim::robot::load_robot_model_file(scene);
  if (model.n != 6) {
    throw teleop::config::ConfigError(scene + ": robot-reach needs a 6-joint arm; it has " +
                                      std::to_string(model.n));
  }
  // the world: the arm and the default scene's planes, advanced by world_step as the server
  // advances its scene
  teleop::sim::WorldModel world;
  world.name = "robot-reach";
  world.slave = teleop::sim::SlaveKind::kRobot;
  world.robot = model;
  world.planes = teleop::sim::robot::default_robot_planes();
  world.robot_options.stepper = stepper == "quick" ? teleop::sim::robot::OdeStepper::kWorldQuickStep
                                                   : teleop::sim::robot::OdeStepper::kWorldStep;
  teleop::sim::WorldData data = teleop::sim::make_world_data(world);
  const RobotSim& sim = *data.robot;
  const std::vector<teleop::sim::Plane>& planes = world.planes;
  // world commands are relative to the tip's home orientation
  const Eigen::Quaterniond home_inv = data.home_orientation.inverse();
  teleop::sim::EventQueue events;

  const double dt = 1e-3;
  const double time_scale = args.quick ? 0.5 : 1.0;
  const std::vector<Waypoint> path = reach_path(sim, model.tip_radius_m);

  teleop::CsvWriter csv((args.out_dir / "robot_reach.csv").string(), reach_columns());
  teleop::CsvWriter ev_csv((args.out_dir / "robot_reach_events.csv").string(),
                           {"t_s", "kind", "value", "message"});

  double t = 0.0;
  ReachStats stats;
  RobotInput in;
  in.mode = ControlMode::kTrackPose;
  teleop::Progress progress("robot-reach", static_cast<double>(path.size() - 1), "segments");
  for (std::size_t w = 1; w < path.size(); ++w) {
    const Waypoint& a = path[w - 1];
    const Waypoint& b = path[w];
    const double move = b.move_s * time_scale;
    const double total = move + b.dwell_s * time_scale;
    const int steps = static_cast<int>(std::lround(total / dt));
    for (int k = 0; k < steps; ++k) {
      set_target(a, b, move, (k + 1) * dt, in);
      teleop::sim::WorldCommand cmd;
      cmd.position_m = in.target_position_m;
      cmd.orientation = home_inv * in.target_orientation;
      cmd.velocity_mps = in.target_velocity_mps;
      cmd.angular_velocity_radps = home_inv * in.target_angular_velocity_radps;
      teleop::sim::world_step(world, data, cmd, dt, events);  // plane contact events included
      t += dt;
      record_step(sim, planes, b, in, t, w, stats, csv);
      write_events(events, ev_csv);
    }
    progress.add();
  }
  progress.finish();
  csv.flush();
  ev_csv.flush();
  write_summary(args, model, stepper, t, stats, sim);

  if (!args.no_chart) {
    teleop::run_chart_script("robot_reach.py", {(args.out_dir / "robot_reach.csv").string(),
                                                (args.out_dir / "robot_reach.png").string()});
  }
  // the experiment fails if the arm never touched both planes or faulted
  if (stats.max_floor_force <= 0.0 || stats.max_wall_force <= 0.0 || sim.state().faults != 0) {
    std::cerr << "robot-reach: the tip did not touch both the floor and the wall, or faulted\n";
    return 1;
  }
  return 0;
}

TELEOP_REGISTER_COMMAND(experiments, "robot-reach",
                        "PUMA 560 slave tip follows a path, presses on the floor and a wall",
                        run_robot_reach, teleop::text_option("--scene", "robot scene YAML"),
                        teleop::text_option("--stepper", "step | quick"));

}  // namespace
