#include "server/world/world.hpp"

#include "server/world/scene_world.hpp"

#include <cmath>

namespace teleop::sim {

ToolWorld::ToolWorld(const SceneConfig& scene) : model_(scene.tool) {
  state_.position_m = scene.tool_start_m;
  state_.hold_position_m = scene.tool_start_m;
  out_.tip_position_m = state_.position_m;
  out_.tracking_kp_n_per_m = model_.kp_n_per_m;
  out_.tracking_kd_ns_per_m = model_.kd_ns_per_m;
}

ToolInput to_tool_input(const WorldCommand& cmd) {
  ToolInput in;
  in.target_position_m = cmd.position_m;
  in.target_orientation = cmd.orientation;
  in.target_velocity_mps = cmd.velocity_mps;
  in.target_angular_velocity_radps = cmd.angular_velocity_radps;
  in.kp_override_n_per_m = cmd.kp_override_n_per_m;
  in.hold = cmd.hold;
  return in;
}

void ToolWorld::step(const WorldCommand& cmd, double dt_s, EventQueue& events) {
  tool_step_checked(model_, state_, to_tool_input(cmd), dt_s, events);

  out_.tip_position_m = state_.position_m;
  out_.tip_orientation = state_.orientation;
  out_.tip_velocity_mps = state_.velocity_mps;
  out_.tip_angular_velocity_radps = state_.angular_velocity_radps;
  out_.contact_force_n = state_.contact_force_n;
  out_.tracking_force_n = state_.tracking_force_n;
  out_.penetration_m = state_.penetration_m;
  out_.contact_object = state_.contact_object;
  out_.in_contact = state_.contact_object >= 0;
  out_.sim_time_s = state_.sim_time_s;
  if (out_.in_contact != was_in_contact_) {
    events.push(out_.in_contact ? EventKind::kContactBegin : EventKind::kContactEnd,
                Severity::kInfo, out_.sim_time_s, out_.contact_object,
                out_.in_contact ? "tool contact begins" : "tool contact ends");
    was_in_contact_ = out_.in_contact;
  }
}

std::unique_ptr<World> make_world(const SceneConfig& scene) {
  // the plain tool-only scene keeps its own small world; anything with a robot or a
  // deformable body is assembled by SceneWorld
  if (scene.kind == "tool" && scene.deformable_nodes.empty()) {
    return std::make_unique<ToolWorld>(scene);
  }
  return std::make_unique<SceneWorld>(scene);
}

}  // namespace teleop::sim
