#include "client/viewer/viewer_session.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <cstdio>

#include "common/dds/guid_text.hpp"
#include "common/util/clock.hpp"

namespace teleop::viewer {

namespace {

/// Frame times kept for the percentiles.
constexpr std::size_t kFrameWindow = 1 << 14;

double per_second(std::uint64_t now, std::uint64_t before, double dt_s) {
  return static_cast<double>(now - before) / dt_s;
}

}  // namespace

void ServerWatch::note(const Prefix& writer, bool slave_state) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (std::find(writers_.begin(), writers_.end(), writer) == writers_.end()) {
    writers_.push_back(writer);
  }
  if (slave_state) {
    server_ = writer;
    have_server_ = true;
  }
}

std::string ServerWatch::server() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return have_server_ ? dds::guid_prefix_text(server_) : std::string();
}

int ServerWatch::writers() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return static_cast<int>(writers_.size());
}

ViewerSession::ViewerSession(double history_s, std::int64_t t0_ns)
    : t0_ns_(t0_ns), data_(history_s, t0_ns), frame_ms_(kFrameWindow) {
  frame_scratch_.reserve(frame_ms_.capacity());
}

void ViewerSession::on_slave_state(const SlaveState& state, const Prefix& writer,
                                   std::int64_t now_ns) {
  servers_.note(writer, true);
  data_.on_slave_state(state, now_ns);
}

void ViewerSession::on_server_stats(const ServerStats& stats, const Prefix& writer,
                                    std::int64_t now_ns) {
  servers_.note(writer, false);
  data_.on_server_stats(stats, now_ns);
}

void ViewerSession::record_frame(std::int64_t start_ns, std::int64_t end_ns) {
  frame_ms_.record(static_cast<double>(end_ns - start_ns) * 1e-6);
  ++frames_;
}

bool ViewerSession::update_rates(std::int64_t now_ns) {
  if (rates_ns_ == 0) {
    rates_ns_ = now_ns;
    last_counters_ = data_.counters();
    return false;
  }
  const double dt = seconds_between(rates_ns_, now_ns);
  if (dt < 1.0) return false;
  const Counters c = data_.counters();
  status_.slave_hz = per_second(c.slave_states, last_counters_.slave_states, dt);
  status_.master_hz = per_second(c.master_states, last_counters_.master_states, dt);
  status_.mesh_hz = per_second(c.frames, last_counters_.frames, dt);
  status_.stats_hz = per_second(c.server_stats, last_counters_.server_stats, dt);
  status_.fps = per_second(frames_, last_frames_, dt);
  status_.server = servers_.server();
  status_.servers = servers_.writers();
  last_frames_ = frames_;
  last_counters_ = c;
  rates_ns_ = now_ns;
  frame_ms_.snapshot_into(frame_scratch_);
  if (!frame_scratch_.empty()) {
    const Summary s = summarize_in_place(frame_scratch_);
    status_.frame_ms_p50 = s.p50;
    status_.frame_ms_p99 = s.p99;
  }
  return true;
}

std::string ViewerSession::frame_summary(const RenderSetup& setup, std::int64_t end_ns,
                                         double cpu_s) const {
  if (frames_ == 0) return "";
  const Summary s = summarize(frame_ms_.snapshot());
  const double span_s = seconds_between(t0_ns_, end_ns);
  const double frames = static_cast<double>(frames_);
  const auto print = [&](char* out, std::size_t size) {
    return std::snprintf(
        out, size,
        "teleop_viewer: %llu frames in %.1f s (%.1f fps); frame time (update + draw + swap) "
        "p50 %.2f ms, p99 %.2f ms, max %.2f ms; CPU %.1f ms per frame (all threads, %.0f%% of a "
        "core); %dx%d, %dx MSAA, %s",
        static_cast<unsigned long long>(frames_), span_s, frames / span_s, s.p50, s.p99, s.max,
        1e3 * cpu_s / frames, 100.0 * cpu_s / span_s, setup.width, setup.height, setup.msaa,
        setup.renderer.c_str());
  };
  const int n = print(nullptr, 0);
  if (n <= 0) return "";
  std::string text(static_cast<std::size_t>(n) + 1, '\0');
  print(text.data(), text.size());
  text.resize(static_cast<std::size_t>(n));
  return text;
}

double process_cpu_s() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

const char* robot_status(const ViewerView& view, int skeleton_joints) {
  if (!view.have_scene()) return "robot: -";
  if (view.scene.joint_count() == 0) return "no robot: a free tool (orange)";
  if (skeleton_joints > 0) return "robot: skeleton from the scene's frames";
  return "robot: tip only (no link frames in the scene)";
}

}  // namespace teleop::viewer
