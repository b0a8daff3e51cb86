#include "client/viewer/frame_timing.hpp"

#include "common/util/clock.hpp"

namespace teleop::viewer {

FramePacer::FramePacer(double fps, bool headless, bool software, std::int64_t start_ns)
    : period_s_(fps > 0.0  ? 1.0 / fps
                : headless ? 1.0 / 30.0
                : software ? 1.0 / 15.0
                           : 0.0),
      next_ns_(start_ns) {}

bool FramePacer::pace_if_unthrottled(double measured_hz, double display_hz) {
  if (period_s_ > 0.0 || display_hz <= 0.0 || measured_hz <= 1.25 * display_hz) return false;
  period_s_ = 1.0 / display_hz;
  return true;
}

std::int64_t FramePacer::sleep_ns(std::int64_t end_ns, std::int64_t now_ns) {
  if (period_s_ <= 0.0) return 0;
  next_ns_ += static_cast<std::int64_t>(period_s_ * 1e9);
  if (next_ns_ < end_ns) next_ns_ = end_ns;  // late: do not catch up
  return next_ns_ > now_ns ? next_ns_ - now_ns : 0;
}

SnapshotFrame SnapshotGate::frame(bool complete, std::int64_t now_ns, double elapsed_s) {
  SnapshotFrame out;
  if (ready_ns_ == 0 && complete) {
    ready_ns_ = now_ns;
    out.became_complete = true;
  }
  if (ready_ns_ != 0) {
    ++frames_since_ready_;
    out.shoot = seconds_between(ready_ns_, now_ns) >= after_s_ && frames_since_ready_ >= kMinFrames;
  } else if (elapsed_s > timeout_s_) {
    out.give_up = true;
  }
  return out;
}

}  // namespace teleop::viewer
