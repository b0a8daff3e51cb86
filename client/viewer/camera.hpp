#pragma once
// The viewer's orbit camera and window layout: pure math, no OpenGL, so tests can tell where a
// world point lands on a snapshot.
//
// World frame: z up (the scenes' convention). The camera orbits `target` at `distance_m`,
// azimuth measured from +x towards +y, elevation from the xy plane.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace teleop::viewer {

struct OrbitCamera {
  Eigen::Vector3f target{0.5f, 0.0f, 0.36f};  ///< point looked at [m]
  float azimuth_rad = -1.05f;                 ///< -60 deg: in front of the scene, to the right
  float elevation_rad = 0.6f;                 ///< 34 deg above the floor: the top of the ball shows
  float distance_m = 2.0f;                    ///< eye to target [m]
  float fov_y_rad = 0.70f;                    ///< vertical field of view (40 deg)
  float near_m = 0.02f;
  float far_m = 50.0f;

  /// Eye position in the world [m].
  Eigen::Vector3f eye() const;
  /// World-to-camera transform (OpenGL convention: the camera looks down its -z).
  Eigen::Matrix4f view() const;
  /// Perspective projection for a viewport of aspect width/height.
  Eigen::Matrix4f projection(float aspect) const;

  /// Pixel position (x right, y down, origin at the viewport's top-left corner) of a world
  /// point in a viewport of vp_w x vp_h pixels. False when the point is behind the camera.
  bool project(const Eigen::Vector3f& p_world, float vp_w, float vp_h, Eigen::Vector2f& px) const;
  /// The ray through pixel `px` (as project() gives it) of a vp_w x vp_h viewport: from the
  /// eye, unit direction. project() of any point on it lands on `px`.
  void ray(const Eigen::Vector2f& px, float vp_w, float vp_h, Eigen::Vector3f& origin,
           Eigen::Vector3f& direction) const;
  /// Unit vector from the eye toward the target.
  Eigen::Vector3f forward() const { return (target - eye()).normalized(); }
  /// Size on screen [px] of a length l [m] at distance along the view axis of point p.
  float pixels_per_metre(const Eigen::Vector3f& p_world, float vp_h) const;

  /// Mouse drag by (dx, dy) pixels: turn around the target.
  void orbit(float dx_px, float dy_px);
  /// Drag by (dx, dy) pixels in a viewport vp_h pixels high: move the target in the view plane.
  void pan(float dx_px, float dy_px, float vp_h);
  /// Scroll by `steps` (positive: closer).
  void zoom(float steps);
};

/// Where the 3-D view and the plot panel go in a window of width x height (logical pixels).
/// The panel is a column on the right; the 3-D view fills the rest.
struct Layout {
  int view_width = 0;   ///< 3-D view: x in [0, view_width), the whole height
  int view_height = 0;  ///< the window height
  int panel_width = 0;  ///< panel: x in [view_width, width); 0 when hidden
};
Layout layout_for(int width, int height, bool panel_shown);

}  // namespace teleop::viewer
