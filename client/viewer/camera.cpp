#include "client/viewer/camera.hpp"

#include <algorithm>
#include <cmath>

namespace teleop::viewer {

Eigen::Vector3f OrbitCamera::eye() const {
  const float ce = std::cos(elevation_rad);
  return target + distance_m * Eigen::Vector3f(ce * std::cos(azimuth_rad),
                                               ce * std::sin(azimuth_rad), std::sin(elevation_rad));
}

Eigen::Matrix4f OrbitCamera::view() const {
  const Eigen::Vector3f e = eye();
  const Eigen::Vector3f f = (target - e).normalized();  // forward
  const Eigen::Vector3f r = f.cross(Eigen::Vector3f::UnitZ()).normalized();
  const Eigen::Vector3f u = r.cross(f);
  Eigen::Matrix4f v = Eigen::Matrix4f::Identity();
  v.block<1, 3>(0, 0) = r.transpose();
  v.block<1, 3>(1, 0) = u.transpose();
  v.block<1, 3>(2, 0) = -f.transpose();
  v(0, 3) = -r.dot(e);
  v(1, 3) = -u.dot(e);
  v(2, 3) = f.dot(e);
  return v;
}

Eigen::Matrix4f OrbitCamera::projection(float aspect) const {
  const float f = 1.0f / std::tan(0.5f * fov_y_rad);
  Eigen::Matrix4f p = Eigen::Matrix4f::Zero();
  p(0, 0) = f / aspect;
  p(1, 1) = f;
  p(2, 2) = (far_m + near_m) / (near_m - far_m);
  p(2, 3) = 2.0f * far_m * near_m / (near_m - far_m);
  p(3, 2) = -1.0f;
  return p;
}

bool OrbitCamera::project(const Eigen::Vector3f& p_world, float vp_w, float vp_h,
                          Eigen::Vector2f& px) const {
  const Eigen::Vector4f clip = projection(vp_w / vp_h) * view() * p_world.homogeneous();
  if (clip.w() <= 1e-6f) return false;
  const float x_ndc = clip.x() / clip.w(), y_ndc = clip.y() / clip.w();
  px.x() = (0.5f * x_ndc + 0.5f) * vp_w;
  px.y() = (0.5f - 0.5f * y_ndc) * vp_h;
  return true;
}

void OrbitCamera::ray(const Eigen::Vector2f& px, float vp_w, float vp_h, Eigen::Vector3f& origin,
                      Eigen::Vector3f& direction) const {
  const float x_ndc = 2.0f * px.x() / vp_w - 1.0f;
  const float y_ndc = 1.0f - 2.0f * px.y() / vp_h;
  const float t = std::tan(0.5f * fov_y_rad);
  const Eigen::Vector3f e = eye();
  const Eigen::Vector3f f = (target - e).normalized();
  const Eigen::Vector3f r = f.cross(Eigen::Vector3f::UnitZ()).normalized();
  const Eigen::Vector3f u = r.cross(f);
  origin = e;
  direction = (f + x_ndc * t * (vp_w / vp_h) * r + y_ndc * t * u).normalized();
}

float OrbitCamera::pixels_per_metre(const Eigen::Vector3f& p_world, float vp_h) const {
  const Eigen::Vector3f e = eye();
  const float depth = (p_world - e).dot((target - e).normalized());
  if (depth <= 1e-6f) return 0.0f;
  return 0.5f * vp_h / (depth * std::tan(0.5f * fov_y_rad));
}

void OrbitCamera::orbit(float dx_px, float dy_px) {
  azimuth_rad -= 0.006f * dx_px;
  elevation_rad = std::clamp(elevation_rad + 0.006f * dy_px, -1.50f, 1.50f);
}

void OrbitCamera::pan(float dx_px, float dy_px, float vp_h) {
  const Eigen::Vector3f e = eye();
  const Eigen::Vector3f f = (target - e).normalized();
  const Eigen::Vector3f r = f.cross(Eigen::Vector3f::UnitZ()).normalized();
  const Eigen::Vector3f u = r.cross(f);
  const float m_per_px = 2.0f * distance_m * std::tan(0.5f * fov_y_rad) / std::max(vp_h, 1.0f);
  target += (-dx_px * r + dy_px * u) * m_per_px;
}

void OrbitCamera::zoom(float steps) {
  distance_m = std::clamp(distance_m * std::pow(0.9f, steps), 0.2f, 30.0f);
}

Layout layout_for(int width, int height, bool panel_shown) {
  Layout l;
  l.view_height = height;
  l.panel_width = panel_shown ? std::clamp(width * 3 / 10, 300, 460) : 0;
  if (l.panel_width > width / 2) l.panel_width = width / 2;  // a narrow window keeps a view
  l.view_width = width - l.panel_width;
  return l;
}

}  // namespace teleop::viewer
