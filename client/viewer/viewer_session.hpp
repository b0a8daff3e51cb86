#pragma once
// What a viewer receives and counts in one run, outside the window: the data store the DDS
// readers fill, which server it watches, the receive rates and frame times the panel shows, and
// the end-of-run summary. The app's readers call on_*() (reader threads); its render loop calls
// record_frame() and update_rates() once per frame.
#include <fastdds/rtps/common/GuidPrefix_t.hpp>

#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "client/viewer/viewer_data.hpp"
#include "common/util/stats.hpp"

namespace teleop::viewer {

/// Which server the viewer watches, from the writers of the server's topics: the participant
/// that wrote the newest slave state, and every participant that wrote any of them (more than
/// one: another server shares the domain, a warning on the panel). Thread-safe; note()
/// allocates only for a writer not seen before.
class ServerWatch {
 public:
  using Prefix = eprosima::fastrtps::rtps::GuidPrefix_t;

  /// A sample of the server's topics written by `writer`; `slave_state`: a SlaveState, whose
  /// writer becomes the server watched.
  void note(const Prefix& writer, bool slave_state);
  /// The server watched as its GUID prefix text ("" before a slave state arrived).
  std::string server() const;
  /// Participants that wrote the server's topics so far.
  int writers() const;

 private:
  mutable std::mutex mutex_;
  bool have_server_ = false;
  Prefix server_;
  std::vector<Prefix> writers_;
};

/// The panel's live figures, refreshed once a second by ViewerSession::update_rates().
struct ReceiveStatus {
  std::string server;  ///< GUID prefix text of the server watched ("" none yet)
  int servers = 0;     ///< participants that wrote the server's topics
  // receive rates over the last refresh period [Hz]
  double slave_hz = 0.0, master_hz = 0.0, mesh_hz = 0.0, stats_hz = 0.0;
  double fps = 0.0;                               ///< frames drawn per second [Hz]
  double frame_ms_p50 = 0.0, frame_ms_p99 = 0.0;  ///< frame times of the recent frames [ms]
};

/// How the frames were drawn, for the summary.
struct RenderSetup {
  int width = 0, height = 0;  ///< framebuffer [px]
  int msaa = 0;               ///< samples per pixel
  std::string renderer;       ///< the OpenGL renderer's name
};

class ViewerSession {
 public:
  using Prefix = ServerWatch::Prefix;

  /// history_s: the plot window [s]; t0_ns: the steady-clock start of the run (plot time 0).
  ViewerSession(double history_s, std::int64_t t0_ns);

  // Reader threads: the samples that name the server; the other topics go to data() directly.
  void on_slave_state(const SlaveState& state, const Prefix& writer, std::int64_t now_ns);
  void on_server_stats(const ServerStats& stats, const Prefix& writer, std::int64_t now_ns);

  ViewerData& data() { return data_; }
  const ViewerData& data() const { return data_; }
  const ServerWatch& servers() const { return servers_; }
  std::int64_t t0_ns() const { return t0_ns_; }

  /// Render thread: one frame drawn from start_ns to end_ns (steady clock).
  void record_frame(std::int64_t start_ns, std::int64_t end_ns);
  /// Frames drawn so far.
  std::uint64_t frames() const { return frames_; }

  /// Render thread, once per frame: the first call starts the count; after that, once at least
  /// a second has passed, refreshes status() from what arrived and was drawn since the last
  /// refresh. Returns true when it refreshed.
  bool update_rates(std::int64_t now_ns);
  const ReceiveStatus& status() const { return status_; }

  /// The end-of-run line: frames and their rate over the run (t0 to end_ns), the frame-time
  /// percentiles, the CPU time per frame and the share of a core (cpu_s: the process's CPU time
  /// [s]), and how the frames were drawn. "" when no frame was drawn.
  std::string frame_summary(const RenderSetup& setup, std::int64_t end_ns, double cpu_s) const;

 private:
  std::int64_t t0_ns_;
  ViewerData data_;
  ServerWatch servers_;
  SampleWindow frame_ms_;
  std::vector<double> frame_scratch_;
  std::uint64_t frames_ = 0, last_frames_ = 0;
  std::int64_t rates_ns_ = 0;
  Counters last_counters_;
  ReceiveStatus status_;
};

/// CPU time of this process so far, all threads, user and system [s].
double process_cpu_s();

/// How the robot is drawn, for the panel: nothing before the scene, a free tool when the scene
/// has no joints, else the skeleton (skeleton_joints > 0: the scene's link frames) or the tip.
const char* robot_status(const ViewerView& view, int skeleton_joints);

}  // namespace teleop::viewer
