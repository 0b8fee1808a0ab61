#pragma once
// What one view of a map is, as the workbench shows it and `vdmap render` draws it: which view,
// where the camera is, how the map is coloured and drawn, which layers, which background. Plain
// structs without parsing (app/view/view_file.* reads and writes them as JSON). The defaults are the
// window's, so the window and a render with no options draw the same picture.
#include <array>
#include <optional>

#include <glm/glm.hpp>

#include "render/scene_types.h"

namespace vdmap::render {

/// The three views: the global map, the map seen from keyframe K, keyframe K's container.
enum class ViewKind { kGlobal, kKeyframe, kContainer };

/// Which world direction the 3-D view keeps up (and orbits about); kData: estimated from the
/// cameras and the map's floor (estimateUp).
enum class UpAxis { kData, kPlusZ, kPlusY, kMinusY };
/// Names in the settings file, view files and --up, indexed by UpAxis.
inline constexpr const char* kUpAxisNames[] = {"data", "+z", "+y", "-y"};

/// How the view projects: a pinhole (perspective), or parallel rays (orthographic: drawn as a
/// camera kOrthographicFar times further away with a lens as much narrower: ViewCamera::lookAt).
enum class Projection { kPerspective, kOrthographic };
inline constexpr const char* kProjectionNames[] = {"perspective", "orthographic"};

/// How dragging turns the view: orbit about the up axis (the horizon stays level), or trackball
/// (free rotation about the image's own axes; the view may roll).
enum class Rotation { kOrbit, kTrackball };
inline constexpr const char* kRotationNames[] = {"orbit", "trackball"};

/// The window's background (dark grey) and the white of printed figures, linear RGB 0..1.
inline constexpr glm::vec3 kDarkBackground{0.13f, 0.13f, 0.15f};
inline constexpr glm::vec3 kWhiteBackground{1.f, 1.f, 1.f};

/// An explicit camera: eye and target in the world frame, `up` the image's up direction.
struct LookAt {
  glm::vec3 eye{0.f}, target{0.f, 0.f, -1.f}, up{0.f, 0.f, 1.f};
  float fov_y_deg = 60.f;
  bool operator==(const LookAt&) const = default;
};

/// The default view turned: angles in degrees about the up axis and above the horizon, as
/// OrbitCamera's yaw and pitch (so -60, 35 is the default view); no distance: the framed one.
struct Orbit {
  float azimuth_deg = -60.f, elevation_deg = 35.f;
  std::optional<float> distance_m;
  bool operator==(const Orbit&) const = default;
};

/// What is drawn besides the map. grid and bounds are the container view's; mesh is the surface
/// mesh of the local maps (docs/method.md 14), off by default.
struct ViewLayers {
  bool frustums = true, graph = true, trajectory = true, groundtruth = true, legend = true;
  bool grid = false, bounds = true, mesh = false;
  bool operator==(const ViewLayers&) const = default;
};

/// The layers' names (--layers, view files) and their fields, in the same order.
inline constexpr const char* kViewLayerNames[] = {"frustums", "graph", "trajectory", "groundtruth",
                                                  "legend",   "grid",  "bounds",     "mesh"};
inline constexpr bool ViewLayers::*kViewLayerFields[] = {
    &ViewLayers::frustums, &ViewLayers::graph, &ViewLayers::trajectory, &ViewLayers::groundtruth,
    &ViewLayers::legend,   &ViewLayers::grid,  &ViewLayers::bounds,     &ViewLayers::mesh};

/// One view, fully described.
struct ViewSpec {
  ViewKind kind = ViewKind::kGlobal;
  int keyframe = -1;              ///< keyframe:K and container:K
  int width = 0, height = 0;      ///< 0: the kind's default size
  std::optional<LookAt> look_at;  ///< an explicit camera (global view); excludes orbit
  std::optional<Orbit> orbit;     ///< the default view turned (global view)
  UpAxis up = UpAxis::kData;
  std::optional<glm::vec3> up_vector;  ///< a user-set world up direction (overrides `up`)
  Projection projection = Projection::kPerspective;
  Rotation rotation = Rotation::kOrbit;  ///< the window's drag; the camera is drawn alike either way
  float fov_y_deg = 60.f;                ///< the framed and orbit views' vertical field of view
  ColorMode color = ColorMode::kRgb;
  bool ellipsoids = true;       ///< false: the ellipsoid centres as points
  bool map_hidden = false;      ///< draw "none": no map at all (overrides `ellipsoids`)
  HeightSlice slice;            ///< heights above the floor drawn (view file v2 "slice")
  float sigma = 2.f;            ///< ellipsoid surfaces at this many standard deviations
  int sphere_level = 0;         ///< icosphere subdivisions (0: icosahedra, as the window)
  float points_below_px = 4.f;  ///< ellipsoids smaller than this are drawn as splats
  ViewLayers layers;
  MeshStyle mesh_style = MeshStyle::kShaded;  ///< how the mesh layer is drawn
  glm::vec3 background = kDarkBackground;
  int selected_keyframe = -1;  ///< drawn white (the window's selection)
  bool operator==(const ViewSpec&) const = default;

  /// The draw mode `ellipsoids` and `map_hidden` spell (kDrawModeNames), and setting it.
  DrawMode draw() const {
    return map_hidden ? DrawMode::kNone : ellipsoids ? DrawMode::kEllipsoids : DrawMode::kCentres;
  }
  void setDraw(DrawMode mode) {
    map_hidden = mode == DrawMode::kNone;
    if (!map_hidden) ellipsoids = mode == DrawMode::kEllipsoids;
  }
};

}  // namespace vdmap::render
