#pragma once
// The scene as teleop_bridge draws it for 3-D panels: the session's topics decoded and turned
// into Foxglove's well-known schemas, JSON encoded (schema encoding jsonschema):
//   foxglove.SceneUpdate      the deformable bodies' triangles (topology + newest mesh frame),
//                             the planes (thin cubes), spheres and boxes, the robot's links
//                             (a line strip through its joint frames, posed from the newest
//                             joint positions, on to the tip), the tip sphere and the
//                             contact-force arrow;
//   foxglove.FrameTransforms  world -> tip and world -> each robot frame;
// and two small JSON channels for the bridge's own page (plots and the event list):
//   teleop.bridge.Plot        contact force, tip position, round trip, in contact;
//   teleop.bridge.Event       one teleop/events sample.
// Samples that do not decode or carry non-finite numbers are ignored and counted.
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "client/viewer/robot_skeleton.hpp"
#include "teleop/idl/Teleop.h"

namespace teleop::bridge {

extern const char* const kSceneUpdateSchema;
extern const char* const kFrameTransformsSchema;
extern const char* const kPlotSchema;
extern const char* const kEventSchema;

class SceneJson {
 public:
  void set_scene(const SceneDescription& scene);
  /// False (and counted) when the indices do not fit the vertex count.
  bool set_topology(const MeshTopology& topology);
  /// False (and counted) when the frame's size does not match its topology or it is not finite.
  bool set_frame(const MeshFrame& frame);
  bool set_slave(const SlaveState& state);
  bool set_master(const MasterState& state);

  /// A scene description has arrived.
  bool ready() const { return have_scene_; }
  /// The period at which the scene is published [s] (the scene's visual rate, 1-30 Hz).
  double period_s() const;
  /// Triangles of the deformable bodies that have a topology.
  std::size_t triangle_count() const;
  std::uint64_t rejected() const { return rejected_; }

  void scene_update(std::string& out, std::uint64_t ns) const;
  void frame_transforms(std::string& out, std::uint64_t ns) const;
  /// False when no state has arrived yet.
  bool plot(std::string& out, std::uint64_t ns) const;

 private:
  struct Body {
    std::vector<std::uint32_t> indices;
    std::uint32_t vertices = 0;
    std::vector<float> positions;  // newest frame, 3 per vertex (empty: none yet)
  };
  void write_bodies(std::string& o) const;
  void write_static(std::string& o) const;
  void write_robot_and_tip(std::string& o) const;

  bool have_scene_ = false, have_slave_ = false, have_master_ = false;
  SceneDescription scene_;
  viewer::RobotSkeleton skeleton_;
  std::map<std::int32_t, Body> bodies_;
  std::array<double, 3> tip_{}, force_{};
  std::array<double, 4> tip_q_{1.0, 0.0, 0.0, 0.0};
  std::vector<double> joints_;
  bool in_contact_ = false;
  double rtt_ms_ = 0.0, sim_time_s_ = 0.0;
  std::uint64_t rejected_ = 0;
};

/// One teleop/events sample as a teleop.bridge.Event JSON object.
std::string event_json(const Event& e);

}  // namespace teleop::bridge
