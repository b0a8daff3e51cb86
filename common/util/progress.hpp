#pragma once
// A one-line progress reporter for the tools' long loops (sweeps, experiments, recordings):
// done/total, rate, elapsed time and ETA, redrawn on stderr with '\r' at most four times a
// second, only when stderr is a terminal (unless forced on or off). Counting is atomic, so the
// workers of a multi-threaded runner call add() themselves; drawing formats into a buffer on the
// stack (no allocation after construction). Not for the 1 kHz loops: a draw writes to a file.
#include <atomic>
#include <cstddef>
#include <cstdio>
#include <functional>

namespace teleop {

/// kAuto: draw when stderr is a terminal; kOn (--progress): always; kOff (--no-progress,
/// --quiet): never.
enum class ProgressMode { kAuto, kOn, kOff };

/// The process-wide mode the tools' command lines set (default kAuto).
void set_progress_mode(ProgressMode mode);
ProgressMode progress_mode();

/// The mode of a tool's flags: --no-progress or --quiet: kOff; --progress: kOn; else kAuto.
ProgressMode progress_mode_from(bool progress, bool no_progress, bool quiet);

/// Whether a reporter draws under `mode` when its stream `is_terminal`.
bool progress_wanted(ProgressMode mode, bool is_terminal);

/// stderr when progress_mode() and stderr's being a terminal say to draw; else nullptr.
std::FILE* progress_stream();

/// A duration for people: "7s", "3m05s", "2h04m" (rounded to the second or the minute);
/// "?" when `s` is negative or not finite. Writes at most `n` bytes (with the NUL) into `buf`.
void format_duration(char* buf, std::size_t n, double s);

/// What one progress line shows.
struct ProgressView {
  const char* label = "";  ///< "delay" ("" for no label)
  const char* unit = "";   ///< "runs", "s"
  double done = 0.0;       ///< how far: runs done, or seconds of a timed run
  double total = 0.0;      ///< how far it goes (0: unknown, no percentage and no ETA)
  double elapsed_s = 0.0;  ///< wall time since the start
  int decimals = 0;        ///< of done and total (1 for a timed run: "4.5/9.0 s")
  bool final = false;      ///< the last line: "done in ..." instead of the ETA
};

/// The line without '\r' or newline, e.g.
///   "delay: 120/500 runs (24.0 %), 6.0 runs/s, 0m20s elapsed, ETA 1m03s"
///   "delay: 500/500 runs (100.0 %), 6.2 runs/s, done in 1m21s"
/// Returns the length written (truncated to fit `n`).
std::size_t format_progress(char* buf, std::size_t n, const ProgressView& v);

class Progress {
 public:
  using Clock = std::function<double()>;  ///< monotonic seconds

  /// A reporter on stderr that draws as progress_mode() and stderr's being a terminal say.
  Progress(const char* label, double total, const char* unit = "runs", int decimals = 0);
  /// A reporter on `out` (nullptr: silent); `clock` replaces the steady clock (tests).
  Progress(std::FILE* out, const char* label, double total, const char* unit, int decimals,
           Clock clock = {});
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  /// Writes the final line if finish() was not called.
  ~Progress();

  /// Counts `n` more done (any thread) and redraws if the last draw is 0.25 s old (the first
  /// call draws at once).
  void add(double n = 1.0);
  /// Sets how far it is (a timed run: seconds so far) and redraws if due.
  void set(double done);
  /// Redraws if due without counting (a loop whose steps are long).
  void poll();
  /// The final line and a newline (once; later calls do nothing).
  void finish();
  /// Whether it draws at all.
  bool active() const { return out_ != nullptr; }
  double done() const { return done_.load(); }
  /// The time since the start (seconds, the reporter's clock).
  double elapsed_s() const;

 private:
  void draw(bool final);
  void draw_if_due();

  std::FILE* out_ = nullptr;
  char label_[48] = {};
  char unit_[16] = {};
  double total_ = 0.0;
  int decimals_ = 0;
  Clock clock_;
  double t0_ = 0.0;
  std::atomic<double> done_{0.0};
  std::atomic<double> next_draw_s_{0.0};
  std::atomic_flag drawing_ = ATOMIC_FLAG_INIT;
  std::size_t last_len_ = 0;
  std::atomic<bool> finished_{false};
};

}  // namespace teleop
