#pragma once
// One thing `vdmap render` (and a suite of views) draws, loaded once and drawn in the process's
// offscreen context.
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "app/cli/sequence_args.h"
#include "mapping/global_map/global_map.h"
#include "mapping/mesh/surface_mesh.h"
#include "render/map_scene.h"
#include "render/query_slice.h"
#include "render/view_spec.h"

namespace vdmap::render {
class MapMirror;
struct Gl;
}  // namespace vdmap::render

namespace vdmap::app {

/// Whether `path` is a map file loadStaticMap reads (a sequence folder, a typo and the rest: no,
/// and they keep their own errors).
bool isStaticMapFile(const std::string& path);

/// One thing to draw, loaded once: a session, a map file (mapping/files/map_file.h), a mesh, or
/// a sequence mapped with `mapper` (the defaults unless --settings or --set change them). Caches what several views of it share.
class RenderSource {
 public:
  /// Opens what the arguments name (SEQ or --map, and/or --mesh); throws InputError. A sequence
  /// is mapped here. `name` is the path errors and the summary use.
  RenderSource(const SequenceArgs& sequence, const std::string& map, const std::string& mesh,
               const MapperParams& mapper = {});
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
  /// Triangles of the --mesh (0 without one) and of the mesh layer when the last render() drew it.
  std::size_t meshTriangles() const;
  /// The global map for `params` (built once per distinct params; a map file's own map).
  const std::vector<Ellipsoid>& globalMap(const GlobalMapParams& params);
  /// The world's up direction for `axis` (kData: estimateUp of the cameras and this map).
  glm::vec3 up(render::UpAxis axis, const GlobalMapParams& params);
  /// The query slice (`--query-slice`; docs/workbench.md "Queries") drawn in every global and
  /// keyframe view from now on (nullopt: none). The point queries are built once per map.
  void setQuerySlice(std::optional<render::QuerySliceSpec> spec);
  /// How the mesh layer's mesh is made from now on (default MeshParams; its sensor model is the
  /// thresholds' filter's).
  void setMeshParams(const MeshParams& params);
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
  /// How the last `data` up axis was found (render::estimateUp); nullopt when the axis was named.
  std::optional<render::UpFrom> lastUpFrom() const { return up_from_; }

 private:
  struct Impl;
  // The slice of `map` (a globalMap() result) at `height`, computed when the map or spec changed.
  std::shared_ptr<const render::QuerySliceImage> querySliceOf(const std::vector<Ellipsoid>& map,
                                                              const render::HeightFrame& height);
  // The mesh layer's surface mesh (docs/method.md 14, setMeshParams') of the map for `params`,
  // built once per map and mesh parameters.
  std::shared_ptr<const render::ColoredMesh> surfaceOf(const GlobalMapParams& params);
  std::unique_ptr<Impl> impl_;
  std::string name_;
  std::size_t last_drawn_ = 0;
  std::size_t last_strays_ = 0;
  glm::vec3 last_up_{0.f, 0.f, 1.f};
  std::optional<render::UpFrom> up_from_;
};

/// The offscreen (OSMesa) GL context of this process, created on first use; throws when OSMesa
/// is missing. Every render of the process draws in it.
const render::Gl& sharedOffscreenGl();

}  // namespace vdmap::app
