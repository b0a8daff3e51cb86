#pragma once
// The framebuffer the viewer draws into: multisampled colour and depth, resolved into the
// window (present) or into a single-sampled buffer read back as an RGB image (snapshots). Drawing
// offscreen makes anti-aliasing independent of what the window system offers.
#include <string>

#include "client/viewer/gl/gl_api.hpp"
#include "client/viewer/png.hpp"

namespace teleop::viewer {

class OffscreenTarget {
 public:
  OffscreenTarget() = default;
  ~OffscreenTarget() { release(); }
  OffscreenTarget(const OffscreenTarget&) = delete;
  OffscreenTarget& operator=(const OffscreenTarget&) = delete;

  /// Creates a width x height target with up to `samples` samples per pixel (0 or 1: none).
  /// Returns false and sets `error` if the driver refuses.
  bool create(int width, int height, int samples, std::string& error);
  /// Makes it the draw framebuffer.
  void bind() const;
  /// Resolves the samples and reads the pixels (top row first) into `out` as RGB.
  void read(Image& out) const;
  /// Resolves the samples into the window's framebuffer (same size).
  void present() const;
  /// Deletes the GL objects (needs the context that created them).
  void release();

  int width() const { return width_; }
  int height() const { return height_; }
  int samples() const { return samples_; }

 private:
  int width_ = 0, height_ = 0, samples_ = 0;
  GLuint draw_fbo_ = 0, color_rb_ = 0, depth_rb_ = 0;
  GLuint resolve_fbo_ = 0, resolve_rb_ = 0;
};

}  // namespace teleop::viewer
