// Google Benchmark micro benchmarks of the slave robot: kinematics, controller, ODE step.
#include <benchmark/benchmark.h>

#include <cmath>

#include "server/robot/robot_sim.hpp"

namespace {

using namespace teleop::sim::robot;

const RobotModel& puma() {
  static const RobotModel m = load_robot_model_file(default_robot_scene_path());
  return m;
}

void BM_RobotForwardKinematics(benchmark::State& state) {
  const RobotModel& m = puma();
  Frames f;
  JointVector q = m.q_home;
  for (auto _ : state) {
    forward_kinematics(m, q, f);
    benchmark::DoNotOptimize(f.tip);
    q(0) += 1e-6;
  }
}
BENCHMARK(BM_RobotForwardKinematics);

void BM_RobotJacobian(benchmark::State& state) {
  const RobotModel& m = puma();
  Frames f;
  forward_kinematics(m, m.q_home, f);
  Jacobian J;
  for (auto _ : state) {
    geometric_jacobian(m, f, J);
    benchmark::DoNotOptimize(J.data());
  }
}
BENCHMARK(BM_RobotJacobian);

void BM_RobotControllerUpdate(benchmark::State& state) {
  const RobotModel& m = puma();
  ControllerState cs;
  controller_reset(m, cs, m.q_home);
  Frames f;
  forward_kinematics(m, m.q_home, f);
  JointCommand cmd;
  RobotInput in;
  in.target_orientation = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()));
  double t = 0.0;
  for (auto _ : state) {
    in.target_position_m = Eigen::Vector3d(0.5 + 0.1 * std::cos(t), 0.1 * std::sin(t), 0.7);
    controller_update(m, cs, in, cs.q_ref, f, 1e-3, t, nullptr, cmd);
    benchmark::DoNotOptimize(cmd.q_ref.data());
    t += 1e-3;
  }
}
BENCHMARK(BM_RobotControllerUpdate);

void BM_RobotSimStep(benchmark::State& state) {
  RobotSimOptions o;
  o.stepper = state.range(0) == 0 ? OdeStepper::kWorldStep : OdeStepper::kWorldQuickStep;
  RobotSim sim(puma(), default_robot_planes(), o);
  RobotInput in;
  in.target_orientation = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()));
  double t = 0.0;
  for (auto _ : state) {
    in.target_position_m = Eigen::Vector3d(0.5 + 0.1 * std::cos(t), 0.1 * std::sin(t), 0.7);
    sim.step(in, 1e-3, nullptr);
    t += 1e-3;
  }
  state.SetLabel(state.range(0) == 0 ? "dWorldStep" : "dWorldQuickStep");
}
BENCHMARK(BM_RobotSimStep)->Arg(0)->Arg(1);

}  // namespace
