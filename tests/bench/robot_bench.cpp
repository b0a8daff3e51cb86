// teleop_bench robot --out DIR [--quick] [--no-chart] [--steps N]
// Step time of the slave robot: the whole RobotSim::step, the ODE call alone (dWorldStep and
// dWorldQuickStep), collision with the planes, and the kinematics + controller alone, in free
// motion (a Cartesian circle) and in contact (tip pressing on the floor). Writes
// robot_bench.csv (median, p90, p99, max per case) and robot_bench.png.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common/config/config.hpp"
#include "common/util/csv.hpp"
#include "common/util/registry.hpp"
#include "common/util/stats.hpp"
#include "server/robot/robot_sim.hpp"

namespace {

using namespace teleop::sim::robot;

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// Commanded input at step k of a scenario.
RobotInput scenario_input(const std::string& scenario, int k, double dt) {
  RobotInput in;
  in.mode = ControlMode::kTrackPose;
  in.target_orientation = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()));
  const double t = k * dt;
  if (scenario == "free") {
    const double w = M_PI;  // 2 s period
    in.target_position_m = Eigen::Vector3d(0.5 + 0.1 * std::cos(w * t), 0.1 * std::sin(w * t), 0.7);
    in.target_velocity_mps = 0.1 * w * Eigen::Vector3d(-std::sin(w * t), std::cos(w * t), 0.0);
  } else {
    // press on the floor 2 cm below the touching height, with a slow sideways wobble
    in.target_orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY()) *
                                               Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()));
    in.target_position_m = Eigen::Vector3d(0.45, 0.05 + 0.02 * std::sin(t), 0.03);
  }
  return in;
}

constexpr double kDt = 1e-3;  // [s]
constexpr int kWarm = 1500;   // steps to reach the circle / the floor before timing

/// Writes one case's row (times given in seconds) and prints it.
class Reporter {
 public:
  explicit Reporter(teleop::CsvWriter& csv) : csv_(csv) {}
  void operator()(const std::string& sc, const std::string& st, const std::string& part,
                  const std::vector<double>& v_s) const {
    std::vector<double> us(v_s.size());
    for (std::size_t i = 0; i < v_s.size(); ++i) us[i] = v_s[i] * 1e6;
    const teleop::Summary s = teleop::summarize(us);
    csv_.row_text({sc, st, part, std::to_string(s.count), teleop::format_number(s.p50),
                   teleop::format_number(s.p90), teleop::format_number(s.p99),
                   teleop::format_number(s.max), teleop::format_number(s.mean)});
    std::printf("  %-8s %-15s %-22s median %7.2f us  p90 %7.2f  p99 %7.2f  max %8.2f\n", sc.c_str(),
                st.c_str(), part.c_str(), s.p50, s.p90, s.p99, s.max);
  }

 private:
  teleop::CsvWriter& csv_;
};

/// The whole step, the ODE call and the collision of `steps` steps of `scenario` with
/// `stepper`, after kWarm steps.
void bench_stepper(const RobotModel& mdl, const std::vector<teleop::sim::Plane>& planes,
                   const std::string& scenario, OdeStepper stepper, int steps,
                   const Reporter& report) {
  const std::string motion = scenario == "contact" ? "contact" : "free";
  const std::string sname = stepper == OdeStepper::kWorldStep ? "dWorldStep" : "dWorldQuickStep";
  RobotSimOptions opt;
  opt.stepper = stepper;
  RobotSim sim(mdl, planes, opt);
  for (int k = 0; k < kWarm; ++k) sim.step(scenario_input(motion, k, kDt), kDt, nullptr);
  std::vector<double> total, ode, coll;
  total.reserve(steps);
  ode.reserve(steps);
  coll.reserve(steps);
  int contact_steps = 0;
  for (int k = 0; k < steps; ++k) {
    const RobotInput in = scenario_input(motion, kWarm + k, kDt);
    const double t0 = now_s();
    sim.step(in, kDt, nullptr);
    total.push_back(now_s() - t0);
    ode.push_back(sim.last_ode_step_s());
    coll.push_back(sim.last_collision_s());
    contact_steps += sim.state().tip_in_contact ? 1 : 0;
  }
  report(scenario, sname, "step_total", total);
  report(scenario, sname, "ode_only", ode);
  report(scenario, sname, "collision", coll);
  std::printf("  (%s: tip in contact in %d of %d steps, faults %llu)\n", scenario.c_str(),
              contact_steps, steps, static_cast<unsigned long long>(sim.state().faults));
}

/// Kinematics + controller alone (no ODE): FK, Jacobian, gravity, DLS IK update.
void bench_kinematics(const RobotModel& model, int steps, const Reporter& report) {
  ControllerState cs;
  controller_reset(model, cs, model.q_home);
  JointVector q = model.q_home;
  Frames f;
  Jacobian J;
  JointCommand cmd;
  std::vector<double> kin, ctl;
  kin.reserve(steps);
  ctl.reserve(steps);
  for (int k = 0; k < steps + kWarm; ++k) {
    const RobotInput in = scenario_input("free", k, kDt);
    const double t0 = now_s();
    forward_kinematics(model, q, f);
    geometric_jacobian(model, f, J);
    const double t1 = now_s();
    controller_update(model, cs, in, q, f, kDt, k * kDt, nullptr, cmd);
    const double t2 = now_s();
    q = cs.q_ref;  // a perfect joint servo
    if (k >= kWarm) {
      kin.push_back(t1 - t0);
      ctl.push_back(t2 - t0);
    }
  }
  report("free", "none", "fk_jacobian", kin);
  report("free", "none", "kinematics_controller", ctl);
}

int run_robot_bench(const teleop::CommandArgs& args) {
  // checked against its range (the registration below) before the run
  const int steps = std::stoi(args.option("--steps", args.quick ? "2000" : "20000"));
  const RobotModel model = load_robot_model_file(default_robot_scene_path());
  const std::vector<teleop::sim::Plane> planes = default_robot_planes();

  teleop::CsvWriter csv((args.out_dir / "robot_bench.csv").string(),
                        {"scenario", "stepper", "part", "samples", "median_us", "p90_us", "p99_us",
                         "max_us", "mean_us"});
  const Reporter report(csv);

  std::printf("robot step time, %d steps per case, dt = 1 ms:\n", steps);
  // the same arm without the Coulomb friction rows (6 fewer constraint rows)
  RobotModel no_coulomb = model;
  for (int i = 0; i < no_coulomb.n; ++i) no_coulomb.links[i].coulomb_nm = 0.0;
  teleop::Progress progress("robot", 7, "cases");
  for (const std::string scenario : {"free", "contact", "free_no_coulomb"}) {
    const RobotModel& mdl = scenario == "free_no_coulomb" ? no_coulomb : model;
    for (const OdeStepper stepper : {OdeStepper::kWorldStep, OdeStepper::kWorldQuickStep}) {
      bench_stepper(mdl, planes, scenario, stepper, steps, report);
      progress.add();
    }
  }
  bench_kinematics(model, steps, report);
  progress.add();
  progress.finish();
  csv.flush();
  if (!args.no_chart) {
    teleop::run_chart_script("robot_bench.py", {(args.out_dir / "robot_bench.csv").string(),
                                                (args.out_dir / "robot_bench.png").string()});
  }
  return 0;
}

TELEOP_REGISTER_COMMAND(bench, "robot",
                        "slave robot step time: ODE dWorldStep / dWorldQuickStep, kinematics",
                        run_robot_bench,
                        teleop::integer_option("--steps", 100, 1e7, "steps per measurement"));

}  // namespace
