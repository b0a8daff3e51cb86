#pragma once
// The viewer's drive and tuning UI (teleop_viewer --drive, Dear ImGui): the master's hand and
// the force it feels drawn over the 3-D view, and a "Drive" window with the force bar, the
// handle, and the tuning form (the values in force and their bounds come from the master's
// teleop/tuning_status; Apply sends what the master's scheme takes).
#include <Eigen/Core>
#include <cstdint>

#include "client/viewer/camera.hpp"
#include "client/viewer/drive_input.hpp"
#include "client/viewer/drive_session.hpp"

namespace teleop::viewer {

/// Draws the master's hand (a ring, filled while dragged) at `hand_world_m` and the force the
/// device renders as an arrow from it (`force_scale_m_per_n`), over a 3-D view of
/// view_w x view_h pixels at the window's top-left.
void draw_drive_overlay(const OrbitCamera& camera, float view_w, float view_h,
                        const Eigen::Vector3d& hand_world_m, const DriveView& drive,
                        double force_scale_m_per_n, bool dragging);

/// Draws the "Drive" window in the 3-D view's top-left corner, below the overlay. Returns the
/// TUNE_* bits to send when Apply was pressed (0 otherwise); the form keeps what was typed.
std::uint32_t draw_drive_window(const DriveView& drive, double peak_force_n, TuningForm& form,
                                float view_h);

}  // namespace teleop::viewer
