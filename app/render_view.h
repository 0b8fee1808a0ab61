#pragma once
// `vdmap render`'s view of a map: the view flags (also a suite view's keys), one loaded source
// shared by several views, and the drawing of one resolved ViewSpec in the process's offscreen
// context. cmd_render.cpp draws one view with it; a suite (render_suite.*) draws many.
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <opencv2/core.hpp>

#include "app/commands.h"
#include "app/gui/settings.h"
#include "mapping/global_map/global_map.h"
#include "mapping/io/ply_reader.h"
#include "mapping/pipeline/mapper.h"
#include "mapping/pipeline/session_file.h"
#include "render/query_slice.h"
#include "render/view_spec.h"

namespace vdmap::render {
class MapMirror;
struct Gl;
}  // namespace vdmap::render

namespace vdmap::app {

/// The view flags of `vdmap render` as given (text, checked while parsing, resolved by
/// resolveViewSpec). Empty / unset: not given, the lower layers of the precedence apply.
struct RenderViewArgs {
  std::string view;              ///< --view global|keyframe:K|container:K (empty: global)
  std::string size;              ///< --size WxH
  std::string color;             ///< --color MODE
  std::string background;        ///< --background dark|white|#rrggbb
  std::string layers;            ///< --layers LIST|none
  std::string up;                ///< --up data|+z|+y|-y, or X,Y,Z with --look-at
  std::string draw;              ///< --draw ellipsoids|centres|none
  std::string slice;             ///< --slice LO:HI
  std::string look_at;           ///< --look-at EX,EY,EZ,TX,TY,TZ
  std::string orbit;             ///< --orbit AZ,EL[,DIST]
  std::string view_file;         ///< --view-file V.json
  std::string settings;          ///< --settings FILE (settings.json or view file: thresholds)
  std::vector<std::string> set;  ///< --set KEY=VALUE
  std::optional<float> fov, sigma, points_below;  ///< --fov, --sigma, --points-below
  std::optional<int> sphere_level, select;        ///< --sphere-level, --select K
  bool grid = false;             ///< --grid (container view's cell grid; as --layers +grid)
};

/// Parses --size WIDTHxHEIGHT (each side 1..kMaxImageSide); throws std::invalid_argument.
std::pair<int, int> parseViewSize(const std::string& text);

/// Registers the view flags on `verb` (or a suite view's parser), writing into `args` (which
/// must outlive the parse). Syntax and ranges are checked while parsing.
void addRenderViewOptions(CLI::App& verb, RenderViewArgs& args);

/// The settings and view a render uses, with the precedence defaults < `session_thresholds` <
/// --settings < --view-file (view only) < flags and --set. `source` says which applied:
/// "defaults", "the session's thresholds", "FILE" or "FILE over the session's thresholds".
struct ResolvedView {
  render::ViewSpec spec;
  GlobalMapParams thresholds;
  std::string settings_source;
};
ResolvedView resolveViewSpec(const RenderViewArgs& args, const std::optional<GlobalMapParams>& session_thresholds);

/// One thing to draw, loaded once: a session, a map file (mapping/export/map_file.h), a mesh, or
/// a sequence mapped with the default parameters. Caches what several views of it share.
class RenderSource {
 public:
  /// Opens what the arguments name (SEQ or --map, and/or --mesh); throws InputError. A sequence
  /// is mapped here. `name` is the path errors and the summary use.
  RenderSource(const SequenceArgs& sequence, const std::string& map, const std::string& mesh);
  ~RenderSource();
  RenderSource(const RenderSource&) = delete;
  RenderSource& operator=(const RenderSource&) = delete;

  const std::string& name() const { return name_; }
  /// The keyframe graph (sessions and sequences); null for a map folder or PLY.
  const KeyframeGraph* graph() const;
  /// The session's own thresholds (nullopt for anything else).
  std::optional<GlobalMapParams> sessionThresholds() const;
  /// Frames mapped (sessions and sequences; 0 otherwise).
  int framesMapped() const;
  /// Triangles of the --mesh (0 without one).
  std::size_t meshTriangles() const;
  /// The global map for `params` (built once per distinct params; a map file's own map).
  const std::vector<Ellipsoid>& globalMap(const GlobalMapParams& params);
  /// The world's up direction for `axis` (kData: estimateUp of the cameras and this map).
  glm::vec3 up(render::UpAxis axis, const GlobalMapParams& params);
  /// The query slice (`--query-slice`; docs/workbench.md "Queries") drawn in every global and
  /// keyframe view from now on (nullopt: none). The point queries are built once per map.
  void setQuerySlice(std::optional<render::QuerySliceSpec> spec);
  /// The slice the last render() drew (null: none).
  const render::QuerySliceImage* lastQuerySlice() const;
  /// Throws std::invalid_argument when `spec` names a keyframe this source lacks.
  void checkView(const render::ViewSpec& spec) const;

  /// Draws `spec` (its size resolved: the kind's default for 0) with `params` in the process's
  /// shared offscreen context; CV_8UC3 RGB. The GPU upload is kept for the next view.
  cv::Mat render(const render::ViewSpec& spec, const GlobalMapParams& params);
  /// The size render() uses for `spec`: its own, else 1280x720 global, the camera's for a
  /// keyframe view, 2W x 2H for a container.
  std::pair<int, int> imageSize(const render::ViewSpec& spec) const;
  /// The number of ellipsoids the last render() drew and the up vector it used (a container
  /// view uses none: the last one stays).
  std::size_t lastDrawn() const { return last_drawn_; }
  /// The ellipsoids the last global view left out of its frame (render::drawnBounds' strays).
  std::size_t lastStrays() const { return last_strays_; }
  glm::vec3 lastUp() const { return last_up_; }

 private:
  struct Impl;
  // The slice of `map` (a globalMap() result) at `height`, computed when the map or spec changed.
  std::shared_ptr<const render::QuerySliceImage> querySliceOf(const std::vector<Ellipsoid>& map,
                                                              const render::HeightFrame& height);
  std::unique_ptr<Impl> impl_;
  std::string name_;
  std::size_t last_drawn_ = 0;
  std::size_t last_strays_ = 0;
  glm::vec3 last_up_{0.f, 0.f, 1.f};
};

/// The offscreen (OSMesa) GL context of this process, created on first use; throws when OSMesa
/// is missing. Every render of the process draws in it.
const render::Gl& sharedOffscreenGl();

}  // namespace vdmap::app
