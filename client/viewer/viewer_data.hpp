#pragma once
// The viewer's data store between the DDS reader threads and the render loop.
//
// Reader callbacks call the on_*() functions: each copies the sample into a pre-sized slot (or
// merges it into a plot series) under a short mutex of its own topic and returns; after the
// first sample of each kind (warm-up) none of them allocates. The render loop calls update()
// once per frame, which copies whatever changed into its own ViewerView (the second buffer):
// the render thread never holds a lock while drawing, and a slow frame never slows a reader.
#include <array>
#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "client/viewer/time_series.hpp"
#include "teleop/idl/Teleop.h"

namespace teleop::viewer {

/// Deformable bodies the viewer can show at once.
inline constexpr int kMaxMeshes = 8;
/// Events kept for the list (newest first).
inline constexpr int kMaxEvents = 64;
/// Points per plot series, whatever the history length.
inline constexpr std::size_t kSeriesPoints = 1500;

/// Plot series, all against the viewer's receive clock [s since the viewer started].
enum Series : int {
  kForceN,         ///< |SlaveState.contact_force_n| [N]
  kPenetrationMm,  ///< SlaveState.penetration_m [mm]
  kDeformationMm,  ///< SlaveState.deformation_m [mm]
  kStepP50Us,      ///< ServerStats.step_us_p50 [us]
  kStepP99Us,      ///< ServerStats.step_us_p99 [us]
  kLoopRateHz,     ///< ServerStats.loop_rate_hz [Hz]
  kRoundTripMs,    ///< MasterState.rtt_ms [ms]
  kEnergyJ,        ///< MasterState.passivity_energy_j [J]
  kSeriesCount
};

/// One event, stored without heap memory.
struct EventEntry {
  double t_s = 0.0;  ///< receive time [s since the viewer started]
  std::uint8_t kind = 0;
  std::uint8_t severity = 0;
  double value = 0.0;
  char source[33] = {};
  char message[257] = {};
};

/// A deformable body: topology (once) and the newest vertex positions.
struct MeshSlot {
  std::int32_t object_id = -1;
  std::uint32_t vertex_count = 0;
  std::vector<std::uint32_t> triangles;  ///< 3 indices per triangle, counter-clockwise outside
  std::vector<float> positions;          ///< newest frame, 3 per vertex, world [m]
  std::vector<float> reference;          ///< first frame received, for displacement colours
  std::uint64_t frame = 0;               ///< MeshFrame.frame of `positions`
  std::uint64_t topology_version = 0;    ///< bumps when the topology changes
  std::uint64_t frame_version = 0;       ///< bumps with every accepted frame

  bool has_topology() const { return topology_version > 0; }
  bool has_frame() const { return frame_version > 0; }
  /// Topology and a frame of the same vertex count: drawable.
  bool drawable() const {
    return has_topology() && has_frame() && positions.size() == 3u * vertex_count &&
           reference.size() == positions.size();
  }
};

/// Samples received and rejected per topic since start.
struct Counters {
  std::uint64_t scenes = 0;
  std::uint64_t topologies = 0;
  std::uint64_t frames = 0;
  std::uint64_t slave_states = 0;
  std::uint64_t master_states = 0;
  std::uint64_t server_stats = 0;
  std::uint64_t events = 0;
  std::uint64_t rejected = 0;  ///< malformed samples ignored (bad indices, sizes, NaN)
};

/// What the render loop draws: its own copy, refreshed by ViewerData::update().
struct ViewerView {
  std::uint64_t scene_version = 0;  ///< 0 until a scene arrived
  SceneDescription scene;
  std::array<MeshSlot, kMaxMeshes> meshes;
  int mesh_count = 0;
  bool have_slave = false;
  SlaveState slave;
  bool have_master = false;
  MasterState master;
  bool have_stats = false;
  ServerStats stats;
  bool have_experiment = false;      ///< a teleop/experiment description arrived (latched)
  ExperimentDescription experiment;  ///< what the session is: scheme, gains, delays, device
  std::uint64_t slave_version = 0, master_version = 0, stats_version = 0;  ///< copied versions
  std::uint64_t experiment_version = 0;
  std::array<EventEntry, kMaxEvents> events;  ///< newest first
  int event_count = 0;
  std::array<TimeSeries, kSeriesCount> series;
  Counters counters;

  bool have_scene() const { return scene_version > 0; }
  /// Mesh slot of a scene object id, or nullptr.
  const MeshSlot* mesh(std::int32_t object_id) const;
  /// True when everything needed to draw the scene has arrived: the scene description, a slave
  /// state and, for every deformable object of the scene, its topology and a frame.
  bool complete() const;
  /// Names of the topics still missing for complete(), e.g. "teleop/scene, teleop/mesh_frame".
  std::string missing() const;
};

class ViewerData {
 public:
  /// history_s: length of the plot window [s]; t0_ns: steady-clock origin of the plot time.
  ViewerData(double history_s, std::int64_t t0_ns);

  // Reader threads. now_ns is the receive time on the steady clock.
  void on_scene(const SceneDescription& scene);
  void on_topology(const MeshTopology& topology);
  void on_mesh_frame(const MeshFrame& frame);
  void on_slave_state(const SlaveState& state, std::int64_t now_ns);
  void on_master_state(const MasterState& state, std::int64_t now_ns);
  void on_server_stats(const ServerStats& stats, std::int64_t now_ns);
  void on_event(const Event& event, std::int64_t now_ns);
  void on_experiment(const ExperimentDescription& experiment);

  /// Render thread: copies what changed since the last call into `view`. Allocation-free once
  /// `view` has seen every kind of sample (capacities are kept).
  void update(ViewerView& view) const;

  /// Samples received so far (readable while the view is paused).
  Counters counters() const;

  /// Plot time [s] of a steady-clock stamp.
  double seconds(std::int64_t t_ns) const;

 private:
  MeshSlot* slot_for(std::int32_t object_id);  // under mesh_mutex_

  std::int64_t t0_ns_;

  mutable std::mutex scene_mutex_;
  std::uint64_t scene_version_ = 0;
  SceneDescription scene_;

  mutable std::mutex mesh_mutex_;
  std::array<MeshSlot, kMaxMeshes> meshes_;
  int mesh_count_ = 0;

  mutable std::mutex slave_mutex_;
  std::uint64_t slave_version_ = 0;
  SlaveState slave_;
  TimeSeries force_, penetration_, deformation_;

  mutable std::mutex master_mutex_;
  std::uint64_t master_version_ = 0;
  MasterState master_;
  TimeSeries rtt_, energy_;

  mutable std::mutex stats_mutex_;
  std::uint64_t stats_version_ = 0;
  ServerStats stats_;
  TimeSeries step_p50_, step_p99_, loop_rate_;

  mutable std::mutex experiment_mutex_;
  std::uint64_t experiment_version_ = 0;
  ExperimentDescription experiment_;

  mutable std::mutex events_mutex_;
  std::array<EventEntry, kMaxEvents> events_;  // ring
  std::uint64_t events_total_ = 0;

  struct AtomicCounters {
    std::atomic<std::uint64_t> scenes{0}, topologies{0}, frames{0}, slave_states{0},
        master_states{0}, server_stats{0}, events{0}, rejected{0};
  };
  AtomicCounters counters_;
};

}  // namespace teleop::viewer
