#pragma once
// When the viewer draws: the frame pacing of the render loop, and when a headless run
// (--snapshot) takes its picture or gives up. Clock values are steady-clock nanoseconds.
#include <cstdint>

namespace teleop::viewer {

/// The frame period: --fps, else the display's vsync. A software renderer is slow enough that
/// a low rate (15 Hz) leaves the CPU to the control loops; a headless run only lays the UI out
/// until its snapshot (30 Hz). A display that does not throttle under vsync (Xvfb, a remote X
/// server) is found after the first frames and paced at its refresh rate.
class FramePacer {
 public:
  /// Frames drawn before the vsync check.
  static constexpr std::uint64_t kVsyncCheckFrames = 120;

  /// fps: --fps [Hz] (0: none asked); start_ns: when the first frame is due.
  FramePacer(double fps, bool headless, bool software, std::int64_t start_ns);

  /// The frame period [s]; 0 while the display's vsync paces.
  double period_s() const { return period_s_; }

  /// Vsync paces and `frames` frames have been drawn: time to see whether the display throttles.
  bool vsync_check_due(std::uint64_t frames) const {
    return period_s_ == 0.0 && frames == kVsyncCheckFrames;
  }
  /// The frames came at `measured_hz`: above 1.25 x `display_hz` the display does not
  /// throttle, and frames are paced at display_hz from now on. Returns true when it switched.
  bool pace_if_unthrottled(double measured_hz, double display_hz);

  /// A frame ended at `end_ns`; it is `now_ns`. How long to sleep before the next frame [ns]
  /// (0: go on). A late frame does not make the next ones catch up.
  std::int64_t sleep_ns(std::int64_t end_ns, std::int64_t now_ns);

 private:
  double period_s_;
  std::int64_t next_ns_;
};

/// What a headless frame does.
struct SnapshotFrame {
  bool became_complete = false;  ///< the data is complete from this frame on (log it)
  bool shoot = false;            ///< draw this frame and write the snapshot
  bool give_up = false;          ///< the data did not become complete within the timeout
};

/// Headless --snapshot: waits for complete data (scene, slave state, every mesh), then after_s
/// more and at least kMinFrames frames (ImGui lays windows out over a frame or two); gives up
/// when the data is not complete after timeout_s.
class SnapshotGate {
 public:
  static constexpr int kMinFrames = 3;

  /// after_s: live data to wait for once complete [s]; timeout_s: the limit for complete data
  /// [s since the start].
  SnapshotGate(double after_s, double timeout_s) : after_s_(after_s), timeout_s_(timeout_s) {}

  /// One frame at `now_ns`, `elapsed_s` after the start, the data `complete` or not.
  SnapshotFrame frame(bool complete, std::int64_t now_ns, double elapsed_s);

 private:
  double after_s_;
  double timeout_s_;
  std::int64_t ready_ns_ = 0;  ///< when the data became complete; 0: not yet
  int frames_since_ready_ = 0;
};

}  // namespace teleop::viewer
