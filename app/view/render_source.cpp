#include "app/view/render_source.h"

#include <cmath>

#include "app/cli/parameter_table.h"
#include "app/view/map_sequence.h"
#include "app/view/view_file.h"
#include "mapping/core/error.h"
#include "mapping/files/map_file.h"
#include "mapping/files/session_file.h"
#include "mapping/mesh/surface_mesh.h"
#include "mapping/pipeline/parameters.h"
#include "render/colormap.h"
#include "render/context.h"
#include "render/map_mirror.h"
#include "render/map_scene.h"
#include "render/mesh_renderer.h"
#include "render/view_draw.h"

namespace vdmap::app {
namespace fs = std::filesystem;

const render::Gl& sharedOffscreenGl() {
  static std::unique_ptr<render::Context> context = render::createOffscreenContext();
  return context->gl();
}

namespace {

// The live parameters' values, the key of the global-map cache.
std::vector<double> paramsKey(const GlobalMapParams& params) {
  ParameterValues values;
  values.global = params;
  std::vector<double> key;
  for (const Parameter& p : parameters())
    if (p.live) key.push_back(p.get(values));
  return key;
}

}  // namespace

bool isStaticMapFile(const std::string& path) {
  try {
    const MapFileKind kind = detectMapFile(path);
    return kind != MapFileKind::kSequence && kind != MapFileKind::kSession && kind != MapFileKind::kViewFile;
  } catch (const InputError&) {
    return false;
  }
}

struct RenderSource::Impl {
  std::optional<Session> session;
  std::unique_ptr<Mapper> mapper;
  const KeyframeGraph* graph = nullptr;
  const MapperState* state = nullptr;
  MapperState mapper_state;  // a mapped sequence's (Mapper::state() is a copy)
  PinholeCamera camera;
  int cell_size_px = 5;
  int frames = 0;
  bool tracked = false;
  std::optional<std::vector<Ellipsoid>> map_file;  // a map file's own ellipsoids
  std::vector<Transform> map_cameras;              // a map folder's trajectory (else keyframes): the data up axis
  std::string map_folder;                          // a `vdmap map` folder's path: its local maps give the mesh layer
  render::GraphScene file_graph;                   // a map folder's keyframes, edges and trajectory
  ColoredTriangleMesh mesh;
  std::vector<std::pair<std::vector<double>, GlobalMap>> maps;  // by paramsKey
  // The query slice (--query-slice): the point queries of the last map asked for (by its
  // paramsKey; empty for a map file's own ellipsoids), and the slice.
  std::optional<render::QuerySliceSpec> query_slice;
  std::optional<std::vector<double>> query_for;
  std::shared_ptr<const QueryMap> query;
  std::shared_ptr<const render::QuerySliceImage> slice_image;
  render::HeightFrame slice_height;  // what slice_image was computed at
  std::unique_ptr<render::MapMirror> mirror;
  int mirror_level = -1;
  std::unique_ptr<render::MeshRenderer> mesh_renderer;
  // The mesh layer's surface mesh of the last map asked for (by its paramsKey).
  std::optional<std::vector<double>> surface_for;
  MeshParams mesh_params, surface_params;  // asked for; what `surface` was made with
  std::shared_ptr<const render::ColoredMesh> surface;
  std::size_t surface_drawn = 0;  // its triangles, when the last view drew it
  int container_serial = 0;
  std::vector<Ellipsoid> sliced;  // the map's ellipsoids a --slice keeps
  int slice_serial = 0;
};

RenderSource::RenderSource(const SequenceArgs& sequence_in, const std::string& map_in, const std::string& mesh,
                           const MapperParams& mapper)
    : impl_(std::make_unique<Impl>()) {
  SequenceArgs sequence = sequence_in;
  std::string map = map_in;
  // A saved session or a map file can stand where SEQ does (as for vdmap gui) or be given as --map.
  if (!sequence.folder.empty() && (isSessionPath(sequence.folder) || isStaticMapFile(sequence.folder)))
    std::swap(map, sequence.folder);
  Impl& m = *impl_;
  if (!map.empty() && isSessionPath(map)) {
    // A container view decodes its keyframe's image; nothing draws the features.
    m.session.emplace(loadSession(map, {.decode_images = false, .keep_features = false}));
    m.graph = &m.session->graph;
    m.state = &m.session->info.state;
    m.camera = m.session->info.camera;
    m.cell_size_px = m.session->info.mapper.local_map.cell_size_px;
    m.frames = m.session->info.state.frames_mapped;
    m.tracked = m.session->info.mapper.poses == PoseSource::kTrack;
    name_ = map;
  } else if (!map.empty()) {
    // A map file (a `vdmap map` folder, an ellipsoid or point PLY, an OctoMap) is drawn by its
    // ellipsoids (mapping/files/map_file.h, as the workbench opens it).
    StaticMap file = loadStaticMap(map);
    // The cameras the window's data up axis uses too (the trajectory, else the keyframes).
    for (const StampedPose& p : file.trajectory.empty() ? file.keyframes : file.trajectory)
      m.map_cameras.push_back(p.T_W_C);
    m.file_graph = render::graphSceneOf(file);
    m.map_file = std::move(file.ellipsoids);
    if (detectMapFile(map) == MapFileKind::kMapFolder) m.map_folder = map;
    name_ = map;
  }
  if (!mesh.empty()) {
    m.mesh = readPlyMesh(mesh);
    if (name_.empty()) name_ = mesh;
  }
  if (!sequence.folder.empty()) {
    const Sequence seq = openSequence(sequence);
    noteCameraGuess(seq, "render");
    MapperParams params = mapper;  // --settings and --set (their re-run keys)
    params.poses = poseSource(sequence, seq);
    checkRefinementApplies(sequence, params.poses);
    m.mapper = std::make_unique<Mapper>(seq.camera(), params);
    mapSequence(seq, *m.mapper, {}, refinement(sequence));
    m.graph = &m.mapper->graph();
    m.mapper_state = m.mapper->state();
    m.state = &m.mapper_state;
    m.camera = seq.camera();
    m.cell_size_px = m.mapper->params().local_map.cell_size_px;
    m.frames = m.mapper->framesMapped();
    m.tracked = params.poses == PoseSource::kTrack;
    name_ = seq.folder().string();
  }
}

RenderSource::~RenderSource() = default;

const KeyframeGraph* RenderSource::graph() const { return impl_->graph; }

std::optional<GlobalMapParams> RenderSource::sessionThresholds() const {
  if (impl_->session) return impl_->session->info.global;
  return std::nullopt;
}

int RenderSource::framesMapped() const { return impl_->frames; }

std::size_t RenderSource::meshTriangles() const { return impl_->mesh.triangles.size() + impl_->surface_drawn; }

const std::vector<Ellipsoid>& RenderSource::globalMap(const GlobalMapParams& params) {
  Impl& m = *impl_;
  if (m.map_file) return *m.map_file;
  static const std::vector<Ellipsoid> kNone;
  if (!m.graph) return kNone;
  const std::vector<double> key = paramsKey(params);
  for (const auto& [k, map] : m.maps)
    if (k == key) return map.ellipsoids;
  m.maps.emplace_back(key, buildGlobalMap(*m.graph, params));
  return m.maps.back().second.ellipsoids;
}

void RenderSource::setQuerySlice(std::optional<render::QuerySliceSpec> spec) {
  impl_->query_slice = std::move(spec);
  impl_->slice_image.reset();
}

std::shared_ptr<const render::QuerySliceImage> RenderSource::querySliceOf(const std::vector<Ellipsoid>& map,
                                                                          const render::HeightFrame& height) {
  Impl& m = *impl_;
  if (!m.query_slice) return nullptr;
  // Which of the built maps `map` is (its address is valid now; kept across calls it would not be).
  const GlobalMap* global = nullptr;
  std::vector<double> key;
  for (const auto& entry : m.maps)
    if (&entry.second.ellipsoids == &map) global = &entry.second, key = entry.first;
  if (m.query_for != key) {
    // The global map's point queries (docs/method.md 13): a map file has no keyframes, so its
    // queries hold the ellipsoids alone (nothing seen free).
    GlobalMap file_map;
    if (!global) file_map.ellipsoids = map, global = &file_map;
    const KeyframeGraph none;
    m.query = std::make_shared<const QueryMap>(
        QueryMap::build(global == &file_map ? none : *m.graph, *global, QueryParams{}));
    m.query_for = key;
    m.slice_image.reset();
  }
  if (!m.slice_image || m.slice_image->spec != *m.query_slice || m.slice_height != height) {
    m.slice_height = height;
    std::optional<render::QuerySliceBox> fallback;
    if (m.query->keyframes() == 0) {
      std::vector<glm::vec3> means;
      means.reserve(map.size());
      for (const Ellipsoid& e : map) means.emplace_back(e.mean.x(), e.mean.y(), e.mean.z());
      const auto [lo, hi] = render::robustBounds(means);
      fallback = render::QuerySliceBox{{lo.x, lo.y, lo.z}, {hi.x, hi.y, hi.z}};
    }
    m.slice_image = std::make_shared<const render::QuerySliceImage>(
        render::computeQuerySlice(*m.query, *m.query_slice, height, fallback));
  }
  return m.slice_image;
}

std::shared_ptr<const render::ColoredMesh> RenderSource::surfaceOf(const GlobalMapParams& params) {
  Impl& m = *impl_;
  const std::vector<double> key = paramsKey(params);
  if (m.surface_for != key || m.surface_params != m.mesh_params) {
    m.surface_for = key;
    m.surface_params = m.mesh_params;
    if (!m.map_folder.empty()) {  // local_maps.ply holds the cells its map kept, with its own thresholds
      MeshParams mesh = m.mesh_params;
      const KeyframeGraph graph = readMapFolderLocalMaps(m.map_folder, &mesh.model);
      std::vector<std::vector<bool>> kept;
      for (const Keyframe& k : graph.keyframes()) kept.emplace_back(k.container.size(), true);
      m.surface =
          std::make_shared<const render::ColoredMesh>(render::toColoredMesh(buildSurfaceMesh(graph, kept, mesh)));
      return m.surface;
    }
    const std::vector<Ellipsoid>& map = globalMap(params);
    for (const auto& entry : m.maps)
      if (&entry.second.ellipsoids == &map)
        m.surface = std::make_shared<const render::ColoredMesh>(
            render::toColoredMesh(buildSurfaceMesh(*m.graph, entry.second, m.mesh_params, params)));
  }
  return m.surface;
}

void RenderSource::setMeshParams(const MeshParams& params) {
  params.validate();
  impl_->mesh_params = params;
}

const render::QuerySliceImage* RenderSource::lastQuerySlice() const { return impl_->slice_image.get(); }

glm::vec3 RenderSource::up(render::UpAxis axis, const GlobalMapParams& params) {
  up_from_.reset();
  if (axis != render::UpAxis::kData) return render::upDirection(axis, {}, {});
  std::vector<Transform> cameras;
  if (impl_->graph) cameras = render::graphSceneOf(*impl_->graph, *impl_->state, impl_->camera, false).trajectory;
  else cameras = impl_->map_cameras;
  render::UpFrom from = render::UpFrom::kCameras;
  const glm::vec3 up = render::estimateUp(cameras, globalMap(params), &from);
  up_from_ = from;
  return up;
}

void RenderSource::checkView(const render::ViewSpec& spec) const {
  const std::size_t keyframes = impl_->graph ? impl_->graph->size() : impl_->file_graph.keyframes.size();
  if (spec.selected_keyframe >= static_cast<int>(keyframes))
    throw std::invalid_argument(
        "--select " + std::to_string(spec.selected_keyframe) + ": " + name_ +
        (keyframes == 0 ? std::string(" has no keyframe") : " has keyframes 0.." + std::to_string(keyframes - 1)));
  if (spec.layers.mesh && !impl_->graph && impl_->map_folder.empty())
    throw std::invalid_argument("--layers mesh draws the surface mesh of local maps: give a sequence (SEQ), a "
                                "session (.vdmap) or a `vdmap map` folder; " +
                                name_ + " has none");
  if (spec.kind == render::ViewKind::kGlobal) return;
  const std::string view = viewName(spec);
  if (!impl_->graph)
    throw std::invalid_argument("--view " + view +
                                " needs keyframes: give a sequence (SEQ) or a session (.vdmap); a --map PLY or map "
                                "folder has none");
  const KeyframeGraph& graph = *impl_->graph;
  if (spec.keyframe >= static_cast<int>(graph.size()))
    throw std::invalid_argument("--view " + view + ": " + name_ +
                                (graph.size() == 0 ? std::string(" has no keyframe")
                                                   : " has keyframes 0.." + std::to_string(graph.size() - 1)));
}

std::pair<int, int> RenderSource::imageSize(const render::ViewSpec& spec) const {
  if (spec.width > 0 && spec.height > 0) return {spec.width, spec.height};
  if (spec.kind == render::ViewKind::kGlobal) return {1280, 720};
  const int scale = spec.kind == render::ViewKind::kContainer ? 2 : 1;
  return {scale * impl_->camera.width, scale * impl_->camera.height};
}

cv::Mat RenderSource::render(const render::ViewSpec& spec_in, const GlobalMapParams& params) {
  checkView(spec_in);
  Impl& m = *impl_;
  m.surface_drawn = 0;
  const render::Gl& gl = sharedOffscreenGl();
  render::ViewSpec spec = spec_in;
  const auto [w, h] = imageSize(spec);
  if (!m.mirror || m.mirror_level != spec.sphere_level) {
    m.mirror = std::make_unique<render::MapMirror>(gl, spec.sphere_level);
    m.mirror_level = spec.sphere_level;
  }
  render::MapMirror& mirror = *m.mirror;
  mirror.setStyle(render::mirrorStyle(spec));
  render::ViewScene scene;
  scene.camera = m.camera;
  if (spec.kind == render::ViewKind::kContainer) {
    const Keyframe& k = m.graph->keyframe(spec.keyframe);
    const std::vector<Ellipsoid> kept = keptEllipsoids(k.container, params.filter, k.T_W_K, k.id);
    mirror.setContainer(++m.container_serial, spec.keyframe, keyframeImage(k, name_), m.camera, k.T_W_K, kept,
                        {.sigma = spec.sigma,
                         .color = spec.color,
                         .cell_size_px = m.cell_size_px,
                         .show_grid = spec.layers.grid,
                         .show_bounds = spec.layers.bounds});
    last_drawn_ = kept.size();
    return render::renderView(gl, mirror, spec, scene, w, h);
  }
  const std::vector<Ellipsoid>& map = globalMap(params);
  // The generation names the map in the cache (a new params key is a new generation).
  int generation = 1;
  for (std::size_t i = 0; i < m.maps.size(); ++i)
    if (&m.maps[i].second.ellipsoids == &map) generation = static_cast<int>(i) + 2;
  // Heights (colours, the slice) are measured from the whole map's floor along the view's up.
  if (spec.up_vector) up_from_.reset();
  scene.up = spec.up_vector ? glm::normalize(*spec.up_vector) : up(spec.up, params);
  scene.height = render::heightFrame(map, scene.up);
  mirror.setStyle(render::mirrorStyle(spec, scene.height));
  // A height slice keeps the ellipsoids whose centre lies lo..hi above the floor, whole.
  const std::vector<Ellipsoid>* shown = &map;
  if (spec.slice.on) {
    m.sliced = render::slicedMap(map, scene.height, spec.slice);
    shown = &m.sliced;
    generation = (1 << 24) + ++m.slice_serial;
  }
  mirror.setMap(generation, *shown);
  mirror.setQuerySlice(querySliceOf(map, scene.height));  // --query-slice (null: none)
  const std::shared_ptr<const render::ColoredMesh> surface = spec.layers.mesh ? surfaceOf(params) : nullptr;
  if (surface) mirror.setSurfaceMesh(surface);
  m.surface_drawn = surface ? surface->triangles.size() : 0;
  render::GraphScene graph = m.file_graph;
  if (m.graph) graph = render::graphSceneOf(*m.graph, *m.state, m.camera, m.tracked);
  graph.selected_keyframe = spec.selected_keyframe;
  mirror.setGraph(1, spec.selected_keyframe, [&] { return graph; });
  if (spec.kind == render::ViewKind::kKeyframe) {
    scene.T_W_K = m.graph->keyframe(spec.keyframe).T_W_K;
    graph.tracked = false;  // the window shows no tracking key through a keyframe
  }
  // The frame holds what is drawn: each ellipsoid's extent at the sigma (strays left out), and a
  // --mesh and the mesh layer whole.
  render::DrawnBounds drawn =
      render::drawnBounds(map, spec.sigma, spec.draw(), spec.slice, scene.height, render::frameAxes(map, scene.up));
  std::vector<glm::vec3> mesh_positions;
  for (const auto& p : m.mesh.positions) mesh_positions.emplace_back(p.x(), p.y(), p.z());
  render::holdPoints(drawn, mesh_positions);
  if (surface) render::holdPoints(drawn, surface->positions);
  last_strays_ = drawn.strays;
  scene.bounds = render::frameBounds(drawn, graph);
  if (spec.look_at && glm::length(spec.look_at->up) < 1e-6f) spec.look_at->up = scene.up;
  last_up_ = spec.look_at ? glm::normalize(spec.look_at->up) : scene.up;
  render::Legend legend;
  if (spec.layers.legend) {
    legend = render::legendFor(spec.color, mirror.mapColorRange(), graph, spec.layers.trajectory,
                               spec.layers.groundtruth, spec.layers.graph);
    if (m.query_slice) render::addQuerySliceKey(legend, *m.query_slice);  // as the window's legend
  }
  mirror.setLegend(legend, spec.background, render::legendPlace(w).max_width);  // as the window places it
  if (!m.mesh.triangles.empty() && !m.mesh_renderer) {
    m.mesh_renderer = std::make_unique<render::MeshRenderer>(gl);
    m.mesh_renderer->set(render::toColoredMesh(m.mesh));
  }
  last_drawn_ = spec.map_hidden ? 0 : shown->size();
  return render::renderView(gl, mirror, spec, scene, w, h, m.mesh_renderer.get());
}

}  // namespace vdmap::app
