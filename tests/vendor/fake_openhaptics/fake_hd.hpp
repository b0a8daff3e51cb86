#pragma once
// Test hooks of the simulated OpenHaptics device (fake_hd.cpp): what the device declares, where
// its handle is, what force the driver last wrote, and faults to inject.
#include <cstdint>

namespace fake_hd {

struct Declared {
  double workspace_mm[6] = {-80, -60, -35, 80, 60, 35};  // minX minY minZ maxX maxY maxZ
  double max_force_n = 3.3;
  double max_continuous_force_n = 0.88;
  double max_stiffness_n_per_mm = 1.26;
  double max_damping_ns_per_mm = 0.0025;
  const char* model = "Fake Touch";
};

/// Resets the fake: the device declares `d`, is at the origin, nothing scheduled.
void reset(const Declared& d = Declared{});
/// The next hdInitDevice fails (no device).
void fail_next_init();
/// From now on, each frame reports a device fault (e.g. a motor over temperature).
void set_fault(bool on);
/// Moves the simulated handle [mm], its velocity [mm/s], buttons.
void set_handle(const double position_mm[3], const double velocity_mm_s[3], int buttons);
/// The last force written with hdSetDoublev(HD_CURRENT_FORCE) [N], and whether output is on.
void last_force(double force_n[3], bool& output_enabled);
/// Servo ticks run so far, and whether the scheduler runs.
std::uint64_t ticks();
bool scheduler_running();

}  // namespace fake_hd
