#include "client/viewer/drive_input.hpp"

namespace teleop::viewer {

namespace {

/// The ray through pixel `px` of the 3-D view, in doubles.
void pixel_ray(const OrbitCamera& camera, const Eigen::Vector2f& px, const Layout& layout,
               Eigen::Vector3d& origin, Eigen::Vector3d& direction) {
  Eigen::Vector3f o, d;
  camera.ray(px, static_cast<float>(layout.view_width), static_cast<float>(layout.view_height), o,
             d);
  origin = o.cast<double>();
  direction = d.cast<double>();
}

}  // namespace

TuningRequest make_tuning_request(const TuningForm& f, std::uint32_t fields) {
  TuningRequest r;
  r.fields(fields);
  r.master_stiffness_n_per_m(f.master_stiffness_n_per_m);
  r.master_damping_ns_per_m(f.master_damping_ns_per_m);
  r.force_gain(f.force_gain);
  r.slave_stiffness_n_per_m(f.slave_stiffness_n_per_m);
  r.forward_delay_ms(f.forward_delay_ms);
  r.backward_delay_ms(f.backward_delay_ms);
  r.ramp_s(f.ramp_s);
  r.source("viewer");
  return r;
}

bool hand_world(const ViewerView& view, Eigen::Vector3d& hand_m) {
  if (!view.have_master) return false;
  const auto& p = view.master.command_position_m();
  hand_m = Eigen::Vector3d(p[0], p[1], p[2]);
  return hand_m.allFinite() && hand_m.squaredNorm() > 0.0;
}

Eigen::Vector3d key_direction(const DriveKeys& k) {
  const auto axis = [](bool plus, bool minus) { return (plus ? 1.0 : 0.0) - (minus ? 1.0 : 0.0); };
  return {axis(k.right, k.left), axis(k.up, k.down), axis(k.page_up, k.page_down)};
}

bool DriveInput::press(const Eigen::Vector2f& px, const ViewerView& view, const OrbitCamera& camera,
                       const Layout& layout) {
  Eigen::Vector3d hand;
  if (!hand_world(view, hand)) return false;
  Eigen::Vector2f at;
  if (!camera.project(hand.cast<float>(), static_cast<float>(layout.view_width),
                      static_cast<float>(layout.view_height), at) ||
      (at - px).norm() > kGrabRadiusPx) {
    return false;
  }
  Eigen::Vector3d o, d;
  pixel_ray(camera, px, layout, o, d);
  target_.grab(hand, camera.forward().cast<double>(), o, d);
  return target_.dragging();
}

void DriveInput::move(const Eigen::Vector2f& px, const OrbitCamera& camera, const Layout& layout) {
  Eigen::Vector3d o, d;
  pixel_ray(camera, px, layout, o, d);
  target_.drag(o, d);
}

bool DriveInput::pointer(const PointerInput& in, bool blocked, const ViewerView& view,
                         const OrbitCamera& camera, const Layout& layout) {
  if (mouse_dragging_) {
    if (in.left_down) {
      move(in.position_px, camera, layout);
    } else {
      target_.release();
      mouse_dragging_ = false;
    }
    return true;
  }
  if (!in.ui_wants_mouse && !blocked && in.left_clicked && !in.shift &&
      press(in.position_px, view, camera, layout)) {
    mouse_dragging_ = true;
    return true;
  }
  return false;
}

}  // namespace teleop::viewer
