#pragma once
// The window's 3-D view image cache (docs/performance.md "Workbench"): a frame that changes only
// the panels (hover, tooltips, the frames ImGui draws after input) copies the last 3-D image
// instead of drawing the map again.
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>

#include <glm/glm.hpp>

#include "render/framebuffer.h"
#include "render/map_mirror.h"
#include "render/view_framing.h"

namespace vdmap::render {

class ViewCache {
 public:
  explicit ViewCache(const Gl& gl);
  ~ViewCache();
  ViewCache(const ViewCache&) = delete;
  ViewCache& operator=(const ViewCache&) = delete;

  /// The picture drawMapView (render/view_draw.h) draws with these arguments, into the bound
  /// draw framebuffer's rectangle `viewport`. It is drawn into the cache's own framebuffer (of
  /// the viewport's size) when anything it depends on changed since the last call: the camera,
  /// the image rectangle, the viewport's size, the background, the lines and legend flags, the
  /// mirror's content serial (every upload, style, highlight or legend change) and its fast
  /// budget; then, or else only, it is copied (glBlitFramebuffer) into `viewport`, colour and
  /// depth (colour only where the target's depth format differs; depthCopied() says). Returns
  /// true when it drew the map.
  bool draw(const MapMirror& mirror, const FramedView& view, const glm::vec3& background, const PixelRect& viewport,
            bool with_lines, bool legend);
  /// The next draw() draws the map.
  void invalidate() { valid_ = false; }
  /// How often draw() drew the map and how often it only copied the image.
  int redraws() const { return redraws_; }
  int blits() const { return blits_; }
  /// Whether the last draw() copied the depth too (else the map's depth is only in image()).
  bool depthCopied() const { return depth_blit_; }
  /// The cached image's framebuffer (colour and depth of the last view drawn; null before any).
  const Framebuffer* image() const { return image_.get(); }
  /// Whether the image held is the fast pass's.
  bool fast() const { return key_.fast_budget > 0; }

 private:
  struct Key {
    glm::mat4 T_C_W{1.f};
    glm::vec4 intrinsics{0.f};  // fx, fy, cx, cy
    glm::vec2 clip{0.f};        // near, far
    PixelRect image{}, viewport{};
    glm::vec3 background{0.f};
    bool with_lines = false, legend = false;
    std::uint64_t content = 0;
    std::size_t fast_budget = 0;
    const MapMirror* mirror = nullptr;
    bool operator==(const Key&) const;
  };
  const Gl* gl_;
  std::unique_ptr<Framebuffer> image_;
  Key key_;
  bool valid_ = false;
  bool depth_probed_ = false, depth_blit_ = false;  // whether the target took the depth copy
  int redraws_ = 0, blits_ = 0;
};

/// When the window draws the fast pass, and how many ellipsoids it draws: from a camera change
/// that leaves the map as it was (a drag, a wheel step, a scripted orbit; not a map that grew
/// and re-framed the view) until kSettleSeconds after the last one, when the full frame is due.
/// The budget adapts to the fast frames' measured times, K <- clamp(K * kTargetMs / ms,
/// kMinBudget, n), unless a fixed budget is given (--fast-budget: scripted runs and tests).
class ViewMotion {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr double kSettleSeconds = 0.15, kTargetMs = 25.0;  // the panels and the swap come on top
  static constexpr std::size_t kMinBudget = 20000, kStartBudget = 100000;
  explicit ViewMotion(std::size_t fixed_budget = 0)
      : fixed_(fixed_budget), budget_(fixed_budget ? fixed_budget : kStartBudget) {}

  /// The camera and the mirror's content serial of the frame about to be drawn at `now`, and
  /// whether the fast pass may be used at all; returns the budget to draw with (0: full
  /// quality). A map of at most kMinBudget ellipsoids (or of at most the fixed budget) is always
  /// drawn at full quality.
  std::size_t frame(const ViewCamera& camera, std::uint64_t content, std::size_t map_size, Clock::time_point now,
                    bool allowed = true);
  /// The fast frame just drawn took `ms` (glFinish-timed): the next budget follows.
  void fastFrameTook(double ms);
  /// Whether a camera change happened within kSettleSeconds of `now`.
  bool moving(Clock::time_point now) const;
  /// When the last frame drawn was fast: seconds from `now` until the full frame is due (0 when
  /// it is overdue); nullopt when the full frame is shown.
  std::optional<double> secondsToFullFrame(Clock::time_point now) const;
  std::size_t budget() const { return budget_; }
  /// When the camera last changed (a default time point before any change).
  Clock::time_point lastMove() const { return last_move_; }

 private:
  struct CameraKey {
    glm::mat4 T_C_W{1.f};
    glm::vec4 intrinsics{0.f};
    bool operator==(const CameraKey&) const = default;
  };
  std::size_t fixed_, budget_;
  std::optional<CameraKey> camera_;
  std::uint64_t content_ = 0;
  Clock::time_point last_move_{};
  bool has_moved_ = false, last_fast_ = false;
};

}  // namespace vdmap::render
