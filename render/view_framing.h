#pragma once
// Where the camera of a view is, the same for the workbench and `vdmap render`: the box a view
// frames, the world's up direction, the default orbit view and the camera a ViewSpec asks for.
#include <cstddef>
#include <span>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "mapping/local_map/ellipsoid_filter.h"
#include "render/scene_lines.h"
#include "render/view_camera.h"
#include "render/view_spec.h"

namespace vdmap::render {

/// The box the global view frames: the 2nd-98th percentile box of the map's means (robustBounds,
/// so a few strays do not shrink the map) grown to hold every keyframe frustum (at
/// kKeyframeFrustumDepthM), every trajectory camera and every ground-truth camera (the cameras
/// are few beside the map and lie off its surfaces: trimmed with it they would be cut at the
/// edge). (-1, 1) when there is nothing.
std::pair<glm::vec3, glm::vec3> frameBounds(std::span<const glm::vec3> means, const GraphScene& graph);

/// What the map part of a framed box is made of: the box of what is drawn and the strays left out.
struct DrawnBounds {
  glm::vec3 lo{0.f}, hi{0.f};  ///< along the columns of `axes`
  glm::mat3 axes{1.f};
  bool empty = true;       ///< nothing drawn (an empty or hidden map, or all sliced away)
  std::size_t drawn = 0;   ///< ellipsoids whose extent the box holds
  std::size_t strays = 0;  ///< left out: centres beyond 1x the robust box's diagonal from its centre
};

/// The box of what the view draws of `map`: per ellipsoid, mean +- sigma sqrt(diag cov) (the
/// exact axis-aligned box of the ellipsoid drawn at sigma) for kEllipsoids, the mean for
/// kCentres, nothing for kNone. Ellipsoids outside `slice` (heights by `frame`) are not drawn,
/// so not framed; strays (centres beyond 1x the diagonal of the robustBounds of the centres from
/// its centre) are left out and counted.
/// The box is along the columns of `axes` (frameAxes: the up axis and the map's horizontal
/// principal directions box a room tightly whatever its walls' angle to the world axes).
DrawnBounds drawnBounds(std::span<const Ellipsoid> map, float sigma, DrawMode mode, const HeightSlice& slice = {},
                        const HeightFrame& frame = {}, const glm::mat3& axes = glm::mat3(1.f));

/// Grows `drawn` to hold `points` (world frame) whole, as a mesh drawn with the map is framed.
void holdPoints(DrawnBounds& drawn, std::span<const glm::vec3> points);

/// The axes a map is boxed along for framing: two horizontal directions, turned about `up` so
/// the box of the means' horizontal 2-98 % extents is smallest (a room's walls), and `up`.
glm::mat3 frameAxes(std::span<const Ellipsoid> map, const glm::vec3& up);

/// The box a view frames: `map` (drawnBounds) grown to hold every keyframe frustum, trajectory
/// camera and ground-truth camera as the overload below; the cameras alone for an empty map.
FrameBox frameBounds(const DrawnBounds& map, const GraphScene& graph);

/// The height frame of a map and an up direction: the floor is the 2nd percentile of
/// dot(mean, up) (0 for an empty map).
HeightFrame heightFrame(std::span<const Ellipsoid> map, const glm::vec3& up);

/// The ellipsoids of `map` a height slice keeps, whole: those whose centre lies lo..hi above the
/// floor of `frame` (all of them when the slice is off). The window's mirror, its picking and
/// `vdmap render --slice` draw this one selection.
std::vector<Ellipsoid> slicedMap(std::span<const Ellipsoid> map, const HeightFrame& frame, const HeightSlice& slice);

/// The world's up direction: the axis named, or for kData estimateUp of the cameras and the map.
glm::vec3 upDirection(UpAxis axis, std::span<const Transform> cameras, std::span<const Ellipsoid> map);

/// The default view of `bounds`: OrbitCamera::framing (yaw -60, pitch 35 degrees about `up`,
/// the box fitted to a width/height `aspect` in the projection given).
OrbitCamera defaultOrbit(const FrameBox& bounds, const glm::vec3& up, float aspect, float fov_y_deg = 60.f,
                         Projection projection = Projection::kPerspective);

/// The preset views: from above, from the front and from the side, turned to the map's
/// horizontal axes (frameAxes: a room's walls).
enum class ViewPreset { kTop, kFront, kSide };
inline constexpr const char* kViewPresetNames[] = {"top", "front", "side"};
/// `cam` turned to `preset` about its target, for a map boxed along `axes` (frameAxes: columns
/// h1, h2 and up): top looks down from 89 degrees (the orbit's limit) with h2 up in the image,
/// front looks level along h2 (h1 to the right), side level along -h1. `up` becomes axes' up;
/// distance, field of view and projection are kept.
void presetView(OrbitCamera& cam, ViewPreset preset, const glm::mat3& axes);

/// What a view's camera is framed from.
struct ViewScene {
  FrameBox bounds;                          ///< frameBounds
  glm::vec3 up{0.f, 0.f, 1.f};              ///< upDirection of the spec's axis
  PinholeCamera camera;                     ///< the keyframes' camera (keyframe views)
  Transform T_W_K = Transform::Identity();  ///< keyframe:K's pose
  HeightFrame height{};                     ///< the map's heightFrame about `up` (height colours, slice)
};

/// A view's camera and where its image lies in the viewport (the letterbox of a keyframe view;
/// the whole viewport otherwise).
struct FramedView {
  ViewCamera camera;
  PixelRect image;
};

/// The camera of `spec` at width x height: its look-at, else its orbit (angles about the up
/// axis, distance framed unless given), else the default view; a keyframe view is the
/// keyframe's own camera letterboxed (fromPinhole). Every global camera is made through
/// OrbitCamera::view, as the window's.
FramedView viewCamera(const ViewSpec& spec, const ViewScene& scene, int width, int height);

/// The orbit camera `spec` describes for a global view (the window's ui.camera).
OrbitCamera orbitCamera(const ViewSpec& spec, const ViewScene& scene, int width, int height);

}  // namespace vdmap::render
