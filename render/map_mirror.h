#pragma once
// The workbench's GPU mirror (the third kind of state, beside the model and the UI state;
// docs/dev/architecture.md): what the window shows of the model, in GPU buffers and
// textures, re-uploaded only when the model's snapshot generations say it changed. The window
// hands it the newest snapshots every UI frame; a generation it has already uploaded costs
// nothing. It owns the renderers, the container view's framebuffer and the image textures;
// screenshots read back through readFramebufferRgb. Use on the thread whose context is current.
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include <opencv2/core.hpp>

#include "mapping/core/camera.h"
#include "mapping/local_map/ellipsoid_filter.h"
#include "render/container_renderer.h"
#include "render/ellipsoid_renderer.h"
#include "render/framebuffer.h"
#include "render/legend.h"
#include "render/mesh_renderer.h"
#include "render/overlay_renderer.h"
#include "render/primitive_renderer.h"
#include "render/query_slice.h"
#include "render/scene_lines.h"
#include "render/texture.h"

namespace vdmap::render {

/// How the 3-D view draws the mirror.
struct MirrorStyle {
  ColorMode color = ColorMode::kRgb;
  float sigma = 2.f;       ///< ellipsoid surfaces at this many standard deviations
  bool ellipsoids = true;  ///< false: the ellipsoid centres as points
  bool map = true;         ///< false: draw mode "none", the map hidden (lines still drawn)
  bool frustums = true, graph = true, trajectory = true;
  bool groundtruth = true;      ///< GraphScene::groundtruth
  float points_below_px = 4.f;  ///< EllipsoidStyle::point_below_px
  HeightFrame height{};         ///< height colours: up axis and floor (heightFrame of the whole map)
  HeightSlice slice{};          ///< height colours: the ramp spans the slice when it is on
  bool mesh = false;            ///< the surface mesh layer (setSurfaceMesh), drawn in mesh_style
  MeshStyle mesh_style = MeshStyle::kShaded;
  bool operator==(const MirrorStyle&) const = default;
};

/// The lines of a keyframe graph as the 3-D view draws them: `lines` (frustums, selected white,
/// current yellow, the camera now red; covisibility edges by weight) and `paths` (loop edges,
/// ground truth, trajectory; drawn wider and on top), each part as the style's toggles say.
struct GraphLines {
  ColoredLines lines, paths;
};
GraphLines graphLines(const GraphScene& scene, const MirrorStyle& style);

/// The range of the colour ramp of a colour mode over a map (ColorRange, legend.h), in the
/// units a legend shows: uncertainty: the largest standard deviation sqrt(lambda_max), m; count:
/// points per ellipsoid; height: heightRange(ellipsoids, height, slice), m above the floor. Empty
/// for rgb / keyframe colours or an empty map.
std::optional<ColorRange> colorRange(std::span<const EllipsoidInstance> ellipsoids, ColorMode mode,
                                     const HeightFrame& height = {}, const HeightSlice& slice = {});

/// Raw depth (CV_16U, `depth_scale` units per metre) as an RGB image: viridis over 0..max_m,
/// black where there is no measurement.
cv::Mat depthToRgb(const cv::Mat& depth, double depth_scale, double max_m);
/// The depth colour ramp's upper end, m (the workbench's depth scale bar shows it).
constexpr double kDepthRampMaxM = 6.0;

/// Reads back the colour of the bound read framebuffer's rectangle (x, y from the bottom-left,
/// GL convention) as CV_8UC3 RGB with row 0 on top (the window's screenshot).
cv::Mat readFramebufferRgb(const Gl& gl, int x, int y, int width, int height);

class MapMirror {
 public:
  /// sphere_level: the ellipsoids' icosphere subdivisions (0: icosahedra, the window's).
  explicit MapMirror(const Gl& gl, int sphere_level = 0);
  ~MapMirror();
  MapMirror(const MapMirror&) = delete;
  MapMirror& operator=(const MapMirror&) = delete;

  /// Restyles (re-sends colours or geometry only when the style asks for it).
  void setStyle(const MirrorStyle& style);
  /// The global map of `generation` (world frame). Uploaded only when the generation differs
  /// from the one shown; generation 0 with an empty span clears the view. `lod_order`: its
  /// lodOrder when the caller computed it (the mapping worker does), else computed here.
  void setMap(int generation, std::span<const Ellipsoid> ellipsoids, std::span<const std::uint32_t> lod_order = {});
  /// The keyframe graph of mapping snapshot `generation`: build() is called, and the lines
  /// re-sent, only when the generation, the selected keyframe or `variant` (anything else the
  /// build depends on, such as which keyframe poses it shows) changed, or the style's
  /// frustum/graph/trajectory/groundtruth toggles.
  void setGraph(int generation, int selected_keyframe, const std::function<GraphScene()>& build, int variant = 0);
  /// The last mapped frame's images (RGB, raw depth) of mapping snapshot `generation`.
  void setFrame(int generation, const cv::Mat& rgb, const cv::Mat& depth, double depth_scale);
  /// The container view (paper Fig. 1) of keyframe `keyframe` (its RGB image, camera, pose and
  /// kept ellipsoids, world frame) for selection `generation`; rendered into containerTexture()
  /// when the generation or the style changed. keyframe < 0 clears it.
  void setContainer(int generation, int keyframe, const cv::Mat& rgb, const PinholeCamera& camera,
                    const Transform& T_W_K, std::span<const Ellipsoid> ellipsoids, const ContainerStyle& style);
  /// The query slice drawn with the map (depth-tested, translucent; docs/workbench.md "Queries"):
  /// uploaded when the pointer differs from the one shown; null: none.
  void setQuerySlice(std::shared_ptr<const QuerySliceImage> slice);
  const QuerySliceImage* querySlice() const { return query_slice_.get(); }
  /// The surface mesh drawn while the style's mesh layer is on: uploaded when the pointer differs
  /// from the one shown; null: none.
  void setSurfaceMesh(std::shared_ptr<const ColoredMesh> mesh);
  /// Marks one ellipsoid (the picked one) with a wire diamond drawn over everything; empty: none.
  /// Re-sent only when the ellipsoid differs from the one marked.
  void setHighlight(const std::optional<Ellipsoid>& ellipsoid);

  /// The legend drawn over the view (rasterised again only when it, the background or the
  /// width changed); an empty legend draws nothing.
  void setLegend(const Legend& legend, const glm::vec3& background, int max_width);

  /// Draws map, lines and highlight into the bound framebuffer's current viewport (whose size
  /// `view` must have). with_lines = false leaves the graph out ("view from keyframe").
  void draw(const ViewCamera& view, bool with_lines = true) const;
  /// While the camera moves the window draws the fast pass (EllipsoidRenderer::drawFast) of
  /// this many ellipsoids; 0 (the default, and always for `vdmap render`): full quality.
  void setFastBudget(std::size_t budget) { fast_budget_ = budget; }
  std::size_t fastBudget() const { return fast_budget_; }
  /// Whether draw() draws the fast pass now (a budget is set and ellipsoids are drawn).
  bool drawsFast() const { return fast_budget_ > 0 && style_.map && style_.ellipsoids && !instances_.empty(); }
  /// Bumped by every change of what draw() and drawLegend() show (uploads, style, highlight,
  /// legend): the view image cache (render/view_cache.h) is keyed by it.
  std::uint64_t contentSerial() const { return content_serial_; }
  const EllipsoidRenderer& ellipsoidRenderer() const { return ellipsoids_; }
  /// Draws the legend at the bottom-left of the current viewport (of `height` pixels).
  void drawLegend(int height) const;
  /// Draws the container set by setContainer into the bound framebuffer at width x height.
  void drawContainer(int width, int height) const;

  const Texture2D& rgbTexture() const { return rgb_; }
  const Texture2D& depthTexture() const { return depth_; }
  /// The container view, 2W x 2H pixels; empty until a keyframe is set.
  const Texture2D& containerTexture() const { return container_image_; }
  /// The same image on the CPU (CV_8UC3 RGB); empty while no keyframe is shown.
  const cv::Mat& containerImage() const { return container_rgb_; }
  /// The shown map's colour ramp range (colorRange of the current colour mode).
  std::optional<ColorRange> mapColorRange() const;
  std::size_t mapSize() const { return instances_.size(); }

  /// How often each part was re-uploaded (tests check that an unchanged generation costs nothing).
  struct Uploads {
    int map = 0, graph = 0, frame = 0, container = 0, mesh = 0;
  };
  const Uploads& uploads() const { return uploads_; }

 private:
  const Gl* gl_;
  MirrorStyle style_;
  EllipsoidRenderer ellipsoids_;
  PointRenderer points_;
  LineRenderer lines_, paths_, highlight_;  // paths_: trajectories and loop edges, wider
  ContainerRenderer container_;
  std::unique_ptr<OverlayRenderer> legend_;
  QuerySliceRenderer query_slice_renderer_;
  std::shared_ptr<const QuerySliceImage> query_slice_;  // what query_slice_renderer_ holds
  std::unique_ptr<MeshRenderer> surface_renderer_;      // made with the first surface mesh
  std::shared_ptr<const ColoredMesh> surface_;          // what surface_renderer_ holds
  Legend legend_shown_;
  glm::vec3 legend_background_{-1.f};
  int legend_width_ = -1;
  cv::Mat legend_image_;
  std::unique_ptr<Framebuffer> container_fb_;
  Texture2D rgb_, depth_, container_image_;
  cv::Mat container_rgb_;
  std::vector<EllipsoidInstance> instances_;
  int map_generation_ = -1, frame_generation_ = -1, container_generation_ = -1;
  int graph_generation_ = -1, graph_selected_ = -2, graph_variant_ = 0;
  MirrorStyle graph_style_, points_style_;
  ContainerStyle container_style_;
  bool has_highlight_ = false;
  std::optional<Ellipsoid> highlighted_;  // what highlight_ holds
  Uploads uploads_;
  std::size_t fast_budget_ = 0;
  std::uint64_t content_serial_ = 0;
};

}  // namespace vdmap::render
