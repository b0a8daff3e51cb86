// libFuzzer target: a MasterCommand as the server receives it, from arbitrary bytes: the DDS
// payload (encapsulation + CDR) deserialized by the type the server's reader registers
// (dds::CheckedType<MasterCommandPubSubType>), then the server's validation
// (validate_command, validate_passivity), from_idl() and the server's conversions on to the tool
// slave (server/world/world_command.hpp). Properties checked:
//   - deserialization of any bytes returns (true or false) and never throws;
//   - a command validate_command() accepts converts to a SlaveCommand whose every field is
//     finite, whose quaternion is a unit quaternion, and whose position lies in the workspace;
//   - one step of the tool slave law driven by an accepted command stays finite.
#include <fastdds/rtps/common/SerializedPayload.h>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "common/dds/checked_type.hpp"
#include "common/dds/teleop_idl.hpp"
#include "common/sim/tool.hpp"
#include "server/node/command_validation.hpp"
#include "server/world/world_command.hpp"
#include "teleop/idl/TeleopPubSubTypes.h"

namespace {
void check(bool ok) {
  if (!ok) __builtin_trap();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size > 4096) return 0;
  eprosima::fastrtps::rtps::SerializedPayload_t payload(static_cast<std::uint32_t>(size));
  if (size > 0) std::memcpy(payload.data, data, size);
  payload.length = static_cast<std::uint32_t>(size);
  teleop::MasterCommand cmd;
  if (!teleop::dds::deserialize_checked<teleop::MasterCommandPubSubType>(payload, cmd)) return 0;

  const Eigen::Vector3d lo(-1.5, -1.5, -0.1), hi(1.5, 1.5, 1.5);  // the default workspace
  const auto verdict = teleop::server::validate_command(cmd, lo, hi, 0, false);
  teleop::server::PassivityHistory history;
  if (verdict != teleop::server::CommandVerdict::kAccepted) return 0;
  (void)teleop::server::validate_passivity(cmd, history);

  const teleop::SlaveCommand c = teleop::from_idl(cmd);
  check(c.position_m.allFinite() && c.velocity_mps.allFinite() &&
        c.angular_velocity_radps.allFinite() && c.master_force_n.allFinite() &&
        c.wave.u.allFinite() && std::isfinite(c.position_gain_n_per_m));
  check(std::abs(c.orientation.norm() - 1.0) < 1e-9);
  check((c.position_m.array() >= lo.array()).all() && (c.position_m.array() <= hi.array()).all());

  teleop::sim::ToolModel tool;
  tool.gravity_mps2 = Eigen::Vector3d(0, 0, -9.81);
  teleop::sim::ToolState state = teleop::sim::tool_state_at(Eigen::Vector3d(0.6, 0.0, 0.7));
  // the server's conversions: command -> world command -> the tool's input
  const teleop::sim::ToolInput in =
      teleop::sim::tool_input(teleop::sim::to_world_command(c), Eigen::Vector3d::Zero());
  teleop::sim::tool_step(tool, state, in, 1e-3);
  check(state.position_m.allFinite() && state.velocity_mps.allFinite() &&
        state.orientation.coeffs().allFinite() && state.angular_velocity_radps.allFinite());
  return 0;
}
