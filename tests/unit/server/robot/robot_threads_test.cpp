// Robots stepped on several threads at once (a campaign runs one session per core): each world
// steps alone, and gives bit for bit what it gives when it is the only one.
#include <gtest/gtest.h>

#include <cmath>
#include <thread>
#include <vector>

#include "server/robot/robot_sim.hpp"
#include "tests/unit/server/robot/robot_test_util.hpp"

namespace teleop::sim::robot {
namespace {

/// Steps a PUMA 560 for 1500 ms toward a target that moves with `phase`; returns its last q.
JointVector drive(const RobotModel& m, double phase) {
  RobotSim sim(m, default_robot_planes());
  RobotInput in;
  in.mode = ControlMode::kTrackPose;
  in.target_orientation = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()));
  for (int k = 0; k < 1500; ++k) {
    const double t = 1e-3 * k;
    in.target_position_m = Eigen::Vector3d(0.6 + 0.05 * std::sin(3.0 * t + phase),
                                           0.05 * std::cos(2.0 * t + phase), 0.6);
    sim.step(in, 1e-3, nullptr);
  }
  return sim.state().q;
}

TEST(RobotSim, WorldsSteppedOnFourThreadsAtOnceAreEachAsAlone) {
  const RobotModel m = testing::puma();
  constexpr int kThreads = 4;
  std::vector<JointVector> alone, together(kThreads);
  for (int i = 0; i < kThreads; ++i) alone.push_back(drive(m, 0.5 * i));
  // a race between worlds need not show in every round
  for (int round = 0; round < 3; ++round) {
    std::vector<std::thread> pool;
    for (int i = 0; i < kThreads; ++i) {
      pool.emplace_back([&, i] { together[i] = drive(m, 0.5 * i); });
    }
    for (std::thread& t : pool) t.join();
    for (int i = 0; i < kThreads; ++i) {
      ASSERT_EQ(together[i].size(), alone[i].size());
      for (int j = 0; j < alone[i].size(); ++j) EXPECT_EQ(together[i](j), alone[i](j)) << i;
    }
  }
  // the targets differ, so do the arms: the comparison is not of four copies of one run
  EXPECT_NE(alone[0](0), alone[1](0));
}

}  // namespace
}  // namespace teleop::sim::robot
