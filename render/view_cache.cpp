#include "render/view_cache.h"

#include <algorithm>

#include "render/view_draw.h"

namespace vdmap::render {

bool ViewCache::Key::operator==(const Key&) const = default;

ViewCache::ViewCache(const Gl& gl) : gl_(&gl) {}

ViewCache::~ViewCache() = default;

bool ViewCache::draw(const MapMirror& mirror, const FramedView& view, const glm::vec3& background,
                     const PixelRect& viewport, bool with_lines, bool legend) {
  const Gl& gl = *gl_;
  const ViewCamera& c = view.camera;
  const Key key{.T_C_W = c.T_C_W,
                .intrinsics = {c.fx, c.fy, c.cx, c.cy},
                .clip = {c.near_m, c.far_m},
                .image = view.image,
                .viewport = {0, 0, viewport.width, viewport.height},  // where it goes does not change it
                .background = background,
                .with_lines = with_lines,
                .legend = legend,
                .content = mirror.contentSerial(),
                .fast_budget = mirror.drawsFast() ? mirror.fastBudget() : 0,
                .mirror = &mirror};
  GLint target = 0;
  gl.GetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &target);
  const bool redraw = !valid_ || !(key == key_);
  if (redraw) {
    if (!image_ || image_->width() != viewport.width || image_->height() != viewport.height)
      image_ = std::make_unique<Framebuffer>(gl, viewport.width, viewport.height);
    gl.BindFramebuffer(GL_FRAMEBUFFER, image_->id());
    drawMapView(gl, mirror, view, background, key.viewport, with_lines, legend);
    key_ = key;
    valid_ = true;
    ++redraws_;
  } else {
    ++blits_;
  }
  gl.BindFramebuffer(GL_READ_FRAMEBUFFER, image_->id());
  gl.BindFramebuffer(GL_DRAW_FRAMEBUFFER, static_cast<GLuint>(target));
  gl.Disable(GL_SCISSOR_TEST);
  // Colour and depth (the depth answers what lies under the cursor); a target whose depth format
  // differs refuses the depth copy once, and gets the colour only from then on.
  auto blit = [&](GLbitfield mask) {
    gl.BlitFramebuffer(0, 0, viewport.width, viewport.height, viewport.x, viewport.y, viewport.x + viewport.width,
                       viewport.y + viewport.height, mask, GL_NEAREST);
  };
  if (!depth_probed_) {  // the first copy finds out (an error earlier in the frame is checked, not kept)
    checkGl(gl, "before the view image's copy");
    blit(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    depth_blit_ = gl.GetError() == GL_NO_ERROR;
    depth_probed_ = true;
    if (!depth_blit_) blit(GL_COLOR_BUFFER_BIT);
  } else {
    blit(depth_blit_ ? GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT : GL_COLOR_BUFFER_BIT);
  }
  gl.BindFramebuffer(GL_FRAMEBUFFER, static_cast<GLuint>(target));
  gl.Viewport(viewport.x, viewport.y, viewport.width, viewport.height);
  return redraw;
}

std::size_t ViewMotion::frame(const ViewCamera& camera, std::uint64_t content, std::size_t map_size,
                              Clock::time_point now, bool allowed) {
  const CameraKey key{camera.T_C_W, {camera.fx, camera.fy, camera.cx, camera.cy}};
  if (camera_ && !(*camera_ == key) && content == content_) {
    last_move_ = now;
    has_moved_ = true;
  }
  camera_ = key;
  content_ = content;
  // Small maps draw fast enough at full quality.
  last_fast_ = allowed && moving(now) && map_size > (fixed_ > 0 ? fixed_ : kMinBudget);
  return last_fast_ ? std::min(budget_, map_size) : 0;
}

void ViewMotion::fastFrameTook(double ms) {
  if (fixed_ > 0 || ms <= 0.0) return;
  const double next = static_cast<double>(budget_) * std::clamp(kTargetMs / ms, 0.5, 2.0);  // no wild swings
  budget_ = std::max(kMinBudget, static_cast<std::size_t>(next));
}

bool ViewMotion::moving(Clock::time_point now) const {
  return has_moved_ && std::chrono::duration<double>(now - last_move_).count() < kSettleSeconds;
}

std::optional<double> ViewMotion::secondsToFullFrame(Clock::time_point now) const {
  if (!last_fast_) return std::nullopt;
  return std::max(0.0, kSettleSeconds - std::chrono::duration<double>(now - last_move_).count());
}

}  // namespace vdmap::render
