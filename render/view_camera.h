#pragma once
// Cameras for drawing. Every view uses the pinhole convention of docs/method.md 1 (camera x right,
// y down, z forward; pixel (u, v) with the origin at the centre of the top-left pixel), so "view
// from keyframe K" with the keyframe's intrinsics reproduces its image pixel for pixel.
#include <optional>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "mapping/core/camera.h"
#include "mapping/core/types.h"

namespace vdmap::render {

/// The orthographic view's distance factor: its eye this many times further from the target than
/// the perspective view's, so a room's depth changes the scale by about a thousandth (under a
/// pixel across a 1280-pixel image) and the depth buffer keeps the perspective view's precision.
inline constexpr float kOrthographicFar = 1000.f;

/// A fully specified view: intrinsics, image size, clip planes and the world-to-camera pose.
struct ViewCamera {
  int width = 640, height = 480;
  float fx = 525.f, fy = 525.f, cx = 319.5f, cy = 239.5f;
  float near_m = 0.05f, far_m = 100.f;
  glm::mat4 T_C_W{1.f};  ///< world -> camera (the view matrix)

  /// Clip-space projection for this pinhole (z in [near, far] -> NDC [-1, 1]; rows are read
  /// back flipped so that image row 0 is the top).
  glm::mat4 projection() const;
  glm::mat4 viewProjection() const { return projection() * T_C_W; }
  /// The camera centre in the world frame.
  glm::vec3 eye() const;

  /// Looks from `eye` at `target` with `up` pointing up in the image; vertical field of view
  /// in degrees, square pixels, principal point at the image centre.
  static ViewCamera lookAt(const glm::vec3& eye, const glm::vec3& target, const glm::vec3& up, float fov_y_deg,
                           int width, int height);
  /// lookAt, or with `orthographic` its parallel projection: the eye kOrthographicFar times
  /// further from the target and the lens as much narrower (the target's plane keeps its scale),
  /// the clip planes those of lookAt moved back with the eye.
  static ViewCamera lookAt(const glm::vec3& eye, const glm::vec3& target, const glm::vec3& up, float fov_y_deg,
                           int width, int height, bool orthographic);
  /// The view of a real camera at pose T_W_C ("view from keyframe K"), rescaled to
  /// width x height (aspect kept by scaling the intrinsics per axis).
  static ViewCamera fromPinhole(const PinholeCamera& camera, const Transform& T_W_C, int width, int height);
};

/// A box to frame: lo..hi along the columns of `axes` (orthonormal; the identity: axis-aligned).
struct FrameBox {
  glm::vec3 lo{-1.f}, hi{1.f};
  glm::mat3 axes{1.f};
  FrameBox() = default;
  FrameBox(const glm::vec3& lo_in, const glm::vec3& hi_in, const glm::mat3& axes_in = glm::mat3(1.f))
      : lo(lo_in), hi(hi_in), axes(axes_in) {}
  FrameBox(const std::pair<glm::vec3, glm::vec3>& box) : lo(box.first), hi(box.second) {}  // NOLINT: axis-aligned
  /// Corner c (bit 0: x, 1: y, 2: z at hi) in the world frame.
  glm::vec3 corner(int c) const {
    return axes * glm::vec3((c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z);
  }
  bool operator==(const FrameBox&) const = default;
};

/// The interactive camera model of the workbench: orbit around a target or fly through the
/// scene. Angles in radians; `up` is the world's up axis.
struct OrbitCamera {
  glm::vec3 target{0.f};
  glm::vec3 up{0.f, 0.f, 1.f};
  float distance_m = 5.f;
  float yaw = 0.f;     ///< around `up`
  float pitch = 0.4f;  ///< above the horizon, clamped to +-89 degrees
  float fov_y_deg = 60.f;
  bool orthographic = false;  ///< view() draws the parallel projection (ViewCamera::lookAt)

  void orbit(float d_yaw, float d_pitch);
  /// Trackball: turns the view about its own image axes (d_yaw about the image's up, d_pitch
  /// about its right), so it may roll; `up` becomes the image's up direction.
  void tumble(float d_yaw, float d_pitch);
  /// The image's up direction (a unit world vector): `up` made perpendicular to the view.
  glm::vec3 imageUp() const;
  /// Moves target and eye together, in the view's right/up plane, by metres.
  void pan(float right_m, float up_m);
  /// Scales the distance (factor < 1 moves closer).
  void dolly(float factor);
  /// Fly mode: moves the eye and target along the viewing direction / right / up by metres.
  void fly(float forward_m, float right_m, float up_m);
  glm::vec3 eye() const;
  ViewCamera view(int width, int height) const;
  /// Keeps the viewing direction and frames the box in a width/height `aspect` view: fit() with
  /// its default margin.
  void frame(const FrameBox& box, float aspect = 1.f) { fit(box, aspect); }
  void frame(const glm::vec3& box_min, const glm::vec3& box_max, float aspect = 1.f) {
    fit(FrameBox(box_min, box_max), aspect);
  }
  /// Keeps the viewing direction and sets target and distance so that all 8 corners of the box
  /// project inside a width/height `aspect` view with `margin` (a fraction of each half-size)
  /// to spare: the distance is the smallest that holds every corner, then the target is shifted
  /// so the projected box is centred (the view's frustum, not the box's bounding sphere).
  /// Orthographic: the distance whose view at the target holds the box's projected extent.
  void fit(const FrameBox& box, float aspect = 1.f, float margin = 0.03f);
  void fit(const glm::vec3& box_min, const glm::vec3& box_max, float aspect = 1.f, float margin = 0.03f) {
    fit(FrameBox(box_min, box_max), aspect, margin);
  }
  /// The default view of a bounding box: from 35 degrees above the horizon, framed as frame().
  static OrbitCamera framing(const FrameBox& box, const glm::vec3& up = {0.f, 0.f, 1.f}, float aspect = 1.f);
  static OrbitCamera framing(const glm::vec3& box_min, const glm::vec3& box_max, const glm::vec3& up = {0.f, 0.f, 1.f},
                             float aspect = 1.f) {
    return framing(FrameBox(box_min, box_max), up, aspect);
  }
  /// The orbit camera looking from `eye` at `target` about the axis `up`: distance |eye - target|,
  /// yaw and pitch inverting eye() (pitch clamped to +-89 degrees, so eye() differs from `eye`
  /// only for a view straight along `up`).
  static OrbitCamera fromLookAt(const glm::vec3& eye, const glm::vec3& target, const glm::vec3& up,
                                float fov_y_deg = 60.f);
};

/// The world point seen at pixel (x_px, y_px) (row 0 on top, pixel centres at integers, as
/// ViewCamera's projection) whose depth-buffer value is depth01 (0 at near, 1 at far: what
/// readDepth returns); nullopt for depth01 >= 1 (no surface) or not finite.
std::optional<glm::vec3> unproject(const ViewCamera& view, float x_px, float y_px, float depth01);

/// A rectangle in pixels.
struct PixelRect {
  int x = 0, y = 0, width = 0, height = 0;
  bool operator==(const PixelRect&) const = default;
};
/// The largest rectangle of aspect image_width : image_height centred in width x height (the
/// letterbox of "view from keyframe": the keyframe's image is neither stretched nor cropped).
PixelRect letterbox(int width, int height, int image_width, int image_height);

/// The box of the central 96% of a point set per axis (2nd to 98th percentile), so a few stray
/// points do not shrink a framed view; (-1, 1) for no points.
std::pair<glm::vec3, glm::vec3> robustBounds(const std::vector<glm::vec3>& points);

/// Eigen -> GLM.
glm::mat4 toGlm(const Transform& T);

}  // namespace vdmap::render
