#include "client/viewer/viewer_data.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "common/dds/topics.hpp"

namespace teleop::viewer {
namespace {

/// Copies a bounded IDL string into a fixed char array, truncating; never allocates.
template <std::size_t N, class Text>
void copy_text(char (&dst)[N], const Text& src) {
  const std::size_t n = std::min<std::size_t>(src.size(), N - 1);
  std::memcpy(dst, src.c_str(), n);
  dst[n] = '\0';
}

/// Copies `src` into `dst`, reusing dst's memory when it is large enough.
template <class T>
void copy_vector(std::vector<T>& dst, const std::vector<T>& src) {
  dst.resize(src.size());
  std::copy(src.begin(), src.end(), dst.begin());
}

double norm3(const std::array<double, 3>& v) {
  return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

}  // namespace

const MeshSlot* ViewerView::mesh(std::int32_t object_id) const {
  for (int i = 0; i < mesh_count; ++i) {
    if (meshes[static_cast<std::size_t>(i)].object_id == object_id) {
      return &meshes[static_cast<std::size_t>(i)];
    }
  }
  return nullptr;
}

bool ViewerView::complete() const { return missing().empty(); }

std::string ViewerView::missing() const {
  std::string out;
  auto add = [&out](const char* what) {
    if (out.find(what) != std::string::npos) return;
    if (!out.empty()) out += ", ";
    out += what;
  };
  if (!have_scene()) add(dds::topics::kScene.name);
  if (!have_slave) add(dds::topics::kSlaveState.name);
  if (have_scene()) {
    for (const auto& o : scene.objects()) {
      if (o.kind() != OBJECT_DEFORMABLE_MESH) continue;
      const MeshSlot* m = mesh(o.id());
      if (m == nullptr || !m->has_topology()) add(dds::topics::kMeshTopology.name);
      if (m == nullptr || !m->drawable()) add(dds::topics::kMeshFrame.name);
    }
  }
  return out;
}

ViewerData::ViewerData(double history_s, std::int64_t t0_ns) : t0_ns_(t0_ns) {
  const double bucket_s = history_s / static_cast<double>(kSeriesPoints);
  for (TimeSeries* s : {&force_, &penetration_, &deformation_, &rtt_, &energy_, &step_p50_,
                        &step_p99_, &loop_rate_}) {
    s->reset(kSeriesPoints + 16, bucket_s);
  }
  // stats arrive at 1-10 Hz: one bucket per sample is plenty
  for (TimeSeries* s : {&step_p50_, &step_p99_, &loop_rate_}) s->reset(kSeriesPoints, 0.05);
}

double ViewerData::seconds(std::int64_t t_ns) const {
  return static_cast<double>(t_ns - t0_ns_) * 1e-9;
}

void ViewerData::on_scene(const SceneDescription& scene) {
  ++counters_.scenes;
  {
    std::lock_guard<std::mutex> lock(scene_mutex_);
    scene_ = scene;
    ++scene_version_;
  }
  // a new scene (a restarted server) starts the displacement reference afresh
  std::lock_guard<std::mutex> lock(mesh_mutex_);
  for (int i = 0; i < mesh_count_; ++i) meshes_[static_cast<std::size_t>(i)].reference.clear();
}

MeshSlot* ViewerData::slot_for(std::int32_t object_id) {
  for (int i = 0; i < mesh_count_; ++i) {
    if (meshes_[static_cast<std::size_t>(i)].object_id == object_id) {
      return &meshes_[static_cast<std::size_t>(i)];
    }
  }
  if (mesh_count_ == kMaxMeshes) return nullptr;
  MeshSlot& s = meshes_[static_cast<std::size_t>(mesh_count_++)];
  s.object_id = object_id;
  return &s;
}

void ViewerData::on_topology(const MeshTopology& topology) {
  const auto& idx = topology.triangle_indices();
  const std::uint32_t n = topology.vertex_count();
  const bool valid = n > 0 && !idx.empty() && idx.size() % 3 == 0 &&
                     std::all_of(idx.begin(), idx.end(), [n](std::uint32_t i) { return i < n; });
  if (!valid) {
    ++counters_.rejected;
    return;
  }
  ++counters_.topologies;
  std::lock_guard<std::mutex> lock(mesh_mutex_);
  MeshSlot* s = slot_for(topology.object_id());
  if (s == nullptr) {
    ++counters_.rejected;
    return;
  }
  if (s->positions.size() != 3u * n) {  // frames of another body under this id: forget them
    s->positions.clear();
    s->reference.clear();
  }
  s->vertex_count = n;
  copy_vector(s->triangles, idx);
  ++s->topology_version;
}

void ViewerData::on_mesh_frame(const MeshFrame& frame) {
  const auto& p = frame.positions_m();
  const bool finite = !p.empty() && p.size() % 3 == 0 &&
                      std::all_of(p.begin(), p.end(), [](float v) { return std::isfinite(v); });
  if (!finite) {
    ++counters_.rejected;
    return;
  }
  ++counters_.frames;
  std::lock_guard<std::mutex> lock(mesh_mutex_);
  MeshSlot* s = slot_for(frame.object_id());
  if (s == nullptr) {
    ++counters_.rejected;
    return;
  }
  copy_vector(s->positions, p);
  if (s->reference.size() != p.size()) copy_vector(s->reference, p);  // first frame
  s->frame = frame.frame();
  ++s->frame_version;
}

void ViewerData::on_slave_state(const SlaveState& state, std::int64_t now_ns) {
  ++counters_.slave_states;
  const double t = seconds(now_ns);
  std::lock_guard<std::mutex> lock(slave_mutex_);
  slave_ = state;  // same sizes after the first sample: the vectors keep their memory
  ++slave_version_;
  force_.add(t, norm3(state.contact_force_n()));
  penetration_.add(t, state.penetration_m() * 1e3);
  deformation_.add(t, state.deformation_m() * 1e3);
}

void ViewerData::on_master_state(const MasterState& state, std::int64_t now_ns) {
  ++counters_.master_states;
  const double t = seconds(now_ns);
  std::lock_guard<std::mutex> lock(master_mutex_);
  master_ = state;
  ++master_version_;
  rtt_.add(t, state.rtt_ms());
  energy_.add(t, state.passivity_energy_j());
}

void ViewerData::on_server_stats(const ServerStats& stats, std::int64_t now_ns) {
  ++counters_.server_stats;
  const double t = seconds(now_ns);
  std::lock_guard<std::mutex> lock(stats_mutex_);
  stats_ = stats;
  ++stats_version_;
  step_p50_.add(t, stats.step_us_p50());
  step_p99_.add(t, stats.step_us_p99());
  loop_rate_.add(t, stats.loop_rate_hz());
}

void ViewerData::on_experiment(const ExperimentDescription& experiment) {
  std::lock_guard<std::mutex> lock(experiment_mutex_);
  experiment_ = experiment;
  ++experiment_version_;
}

void ViewerData::on_event(const Event& event, std::int64_t now_ns) {
  ++counters_.events;
  std::lock_guard<std::mutex> lock(events_mutex_);
  EventEntry& e = events_[static_cast<std::size_t>(events_total_ % kMaxEvents)];
  e.t_s = seconds(now_ns);
  e.kind = event.kind();
  e.severity = event.severity();
  e.value = event.value();
  copy_text(e.source, event.source());
  copy_text(e.message, event.message());
  ++events_total_;
}

void ViewerData::update(ViewerView& view) const {
  {
    std::lock_guard<std::mutex> lock(scene_mutex_);
    if (scene_version_ != view.scene_version) {
      view.scene = scene_;
      view.scene_version = scene_version_;
    }
  }
  {
    std::lock_guard<std::mutex> lock(mesh_mutex_);
    view.mesh_count = mesh_count_;
    for (int i = 0; i < mesh_count_; ++i) {
      const MeshSlot& src = meshes_[static_cast<std::size_t>(i)];
      MeshSlot& dst = view.meshes[static_cast<std::size_t>(i)];
      dst.object_id = src.object_id;
      dst.vertex_count = src.vertex_count;
      if (dst.topology_version != src.topology_version) {
        copy_vector(dst.triangles, src.triangles);
        dst.topology_version = src.topology_version;
      }
      if (dst.frame_version != src.frame_version || dst.reference.size() != src.reference.size()) {
        copy_vector(dst.positions, src.positions);
        copy_vector(dst.reference, src.reference);
        dst.frame = src.frame;
        dst.frame_version = src.frame_version;
      }
    }
  }
  {
    std::lock_guard<std::mutex> lock(slave_mutex_);
    if (slave_version_ != view.slave_version) {
      view.slave_version = slave_version_;
      view.slave = slave_;
      view.have_slave = true;
      view.series[kForceN].copy_from(force_);
      view.series[kPenetrationMm].copy_from(penetration_);
      view.series[kDeformationMm].copy_from(deformation_);
    }
  }
  {
    std::lock_guard<std::mutex> lock(master_mutex_);
    if (master_version_ != view.master_version) {
      view.master_version = master_version_;
      view.master = master_;
      view.have_master = true;
      view.series[kRoundTripMs].copy_from(rtt_);
      view.series[kEnergyJ].copy_from(energy_);
    }
  }
  {
    std::lock_guard<std::mutex> lock(stats_mutex_);
    if (stats_version_ != view.stats_version) {
      view.stats_version = stats_version_;
      view.stats = stats_;
      view.have_stats = true;
      view.series[kStepP50Us].copy_from(step_p50_);
      view.series[kStepP99Us].copy_from(step_p99_);
      view.series[kLoopRateHz].copy_from(loop_rate_);
    }
  }
  {
    std::lock_guard<std::mutex> lock(experiment_mutex_);
    if (experiment_version_ != view.experiment_version) {
      view.experiment_version = experiment_version_;
      view.experiment = experiment_;
      view.have_experiment = true;
    }
  }
  {
    std::lock_guard<std::mutex> lock(events_mutex_);
    const auto n = static_cast<int>(std::min<std::uint64_t>(events_total_, kMaxEvents));
    for (int i = 0; i < n; ++i) {  // newest first
      view.events[static_cast<std::size_t>(i)] = events_[static_cast<std::size_t>(
          (events_total_ - 1 - static_cast<std::uint64_t>(i)) % kMaxEvents)];
    }
    view.event_count = n;
  }
  view.counters = counters();
}

Counters ViewerData::counters() const {
  Counters c;
  c.scenes = counters_.scenes.load();
  c.topologies = counters_.topologies.load();
  c.frames = counters_.frames.load();
  c.slave_states = counters_.slave_states.load();
  c.master_states = counters_.master_states.load();
  c.server_stats = counters_.server_stats.load();
  c.events = counters_.events.load();
  c.rejected = counters_.rejected.load();
  return c;
}

}  // namespace teleop::viewer
