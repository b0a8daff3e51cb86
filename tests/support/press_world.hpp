#pragma once
// The press scenarios (client/analysis/press_scenario.hpp) against the server's world: the
// slave of every in-process session in the tests and the delay sweep is server::WorldSlave
// (ServerCycle + world_step) on the scenario's tool world.
#include "client/analysis/press_scenario.hpp"
#include "server/node/world_slave.hpp"
#include "server/world/world_model.hpp"

namespace teleop::test {

/// The tool-only world of a press setup (floor and object as the tool's obstacles), at the
/// loop's rate; the slave starts where the master origin maps (LoopbackSession::start moves
/// it to the device's mapped position).
inline sim::WorldModel press_world(const master::PressSetup& setup) {
  return sim::tool_world_model(setup.slave, setup.loop.controller.workspace.offset_m,
                               1.0 / setup.loop.dt_s);
}

/// Builds and runs scenario `s` against the server's world.
inline master::PressResult run_press_world(const master::PressScenario& s) {
  const master::PressSetup setup = master::build_press_setup(s);
  server::WorldSlave slave(press_world(setup), setup.loop.dt_s);
  return master::run_press(s, setup, slave);
}

}  // namespace teleop::test
