#include "client/viewer/gl/offscreen.hpp"

#include <algorithm>
#include <cstring>
#include <vector>

namespace teleop::viewer {

bool OffscreenTarget::create(int width, int height, int samples, std::string& error) {
  release();
  GLint max_samples = 0;
  glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
  samples_ = std::clamp(samples, 0, static_cast<int>(max_samples));
  if (samples_ == 1) samples_ = 0;
  width_ = width;
  height_ = height;

  glGenRenderbuffers(1, &color_rb_);
  glBindRenderbuffer(GL_RENDERBUFFER, color_rb_);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples_, GL_RGBA8, width, height);
  glGenRenderbuffers(1, &depth_rb_);
  glBindRenderbuffer(GL_RENDERBUFFER, depth_rb_);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples_, GL_DEPTH24_STENCIL8, width, height);
  glGenFramebuffers(1, &draw_fbo_);
  glBindFramebuffer(GL_FRAMEBUFFER, draw_fbo_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color_rb_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER,
                            depth_rb_);
  const GLenum draw_status = glCheckFramebufferStatus(GL_FRAMEBUFFER);

  glGenRenderbuffers(1, &resolve_rb_);
  glBindRenderbuffer(GL_RENDERBUFFER, resolve_rb_);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, width, height);
  glGenFramebuffers(1, &resolve_fbo_);
  glBindFramebuffer(GL_FRAMEBUFFER, resolve_fbo_);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, resolve_rb_);
  const GLenum resolve_status = glCheckFramebufferStatus(GL_FRAMEBUFFER);

  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glBindRenderbuffer(GL_RENDERBUFFER, 0);
  if (draw_status != GL_FRAMEBUFFER_COMPLETE || resolve_status != GL_FRAMEBUFFER_COMPLETE) {
    error = "offscreen framebuffer of " + std::to_string(width) + "x" + std::to_string(height) +
            " with " + std::to_string(samples_) + " samples is incomplete";
    release();
    return false;
  }
  return true;
}

void OffscreenTarget::bind() const { glBindFramebuffer(GL_FRAMEBUFFER, draw_fbo_); }

void OffscreenTarget::read(Image& out) const {
  glBindFramebuffer(GL_READ_FRAMEBUFFER, draw_fbo_);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, resolve_fbo_);
  glBlitFramebuffer(0, 0, width_, height_, 0, 0, width_, height_, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, resolve_fbo_);
  const auto w = static_cast<std::size_t>(width_), h = static_cast<std::size_t>(height_);
  std::vector<std::uint8_t> rgba(w * h * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  // OpenGL rows start at the bottom; PNG rows at the top
  out.width = width_;
  out.height = height_;
  out.channels = 3;
  out.pixels.resize(w * h * 3);
  for (std::size_t y = 0; y < h; ++y) {
    const std::uint8_t* src = rgba.data() + (h - 1 - y) * w * 4;
    std::uint8_t* dst = out.pixels.data() + y * w * 3;
    for (std::size_t x = 0; x < w; ++x) std::memcpy(dst + 3 * x, src + 4 * x, 3);
  }
}

void OffscreenTarget::present() const {
  glBindFramebuffer(GL_READ_FRAMEBUFFER, draw_fbo_);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
  glBlitFramebuffer(0, 0, width_, height_, 0, 0, width_, height_, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void OffscreenTarget::release() {
  if (draw_fbo_) glDeleteFramebuffers(1, &draw_fbo_);
  if (resolve_fbo_) glDeleteFramebuffers(1, &resolve_fbo_);
  for (GLuint* rb : {&color_rb_, &depth_rb_, &resolve_rb_}) {
    if (*rb) glDeleteRenderbuffers(1, rb);
    *rb = 0;
  }
  draw_fbo_ = resolve_fbo_ = 0;
}

}  // namespace teleop::viewer
