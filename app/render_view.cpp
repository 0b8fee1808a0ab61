#include "app/render_view.h"

#include <cmath>
#include <regex>

#include "app/map_sequence.h"
#include "app/parameter_table.h"
#include "mapping/pipeline/parameters.h"
#include "app/view_file.h"
#include "mapping/core/error.h"
#include "mapping/export/map_file.h"
#include "render/colormap.h"
#include "render/context.h"
#include "render/map_mirror.h"
#include "render/map_scene.h"
#include "render/mesh_renderer.h"
#include "render/view_draw.h"

namespace vdmap::app {
namespace fs = std::filesystem;

namespace {

const char* const kLayerNames[] = {"frustums", "graph", "trajectory", "groundtruth", "legend", "grid", "bounds"};
bool render::ViewLayers::*const kLayerFields[] = {
    &render::ViewLayers::frustums, &render::ViewLayers::graph,  &render::ViewLayers::trajectory,
    &render::ViewLayers::groundtruth, &render::ViewLayers::legend, &render::ViewLayers::grid,
    &render::ViewLayers::bounds};

// Comma-separated finite numbers, `min_count`..`max_count` of them.
std::vector<float> parseNumbers(const std::string& text, std::size_t min_count, std::size_t max_count,
                                const std::string& form) {
  std::vector<float> out;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    std::size_t used = 0;
    float v = 0;
    try {
      v = std::stof(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (item.empty() || used != item.size() || !std::isfinite(v))
      throw std::invalid_argument("'" + text + "': expected " + form + " (finite numbers)");
    out.push_back(v);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (out.size() < min_count || out.size() > max_count) throw std::invalid_argument("'" + text + "': expected " + form);
  return out;
}

render::ViewLayers parseLayers(const std::string& text) {
  render::ViewLayers layers;
  for (bool render::ViewLayers::*f : kLayerFields) layers.*f = false;
  if (text == "none") return layers;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    bool known = false;
    for (std::size_t i = 0; i < std::size(kLayerNames); ++i)
      if (item == kLayerNames[i]) layers.*kLayerFields[i] = known = true;
    if (!known)
      throw std::invalid_argument("'" + item + "': expected none or a comma-separated list of frustums, graph, "
                                  "trajectory, groundtruth, legend, grid, bounds");
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return layers;
}

std::optional<render::UpAxis> parseUpAxis(const std::string& text) {
  for (int i = 0; i < 4; ++i)
    if (text == render::kUpAxisNames[i]) return static_cast<render::UpAxis>(i);
  return std::nullopt;
}

// --up: an axis name, or (with --look-at) the image's up vector X,Y,Z.
void checkUp(const std::string& text) {
  if (parseUpAxis(text)) return;
  const std::vector<float> v = parseNumbers(text, 3, 3, "data, +z, +y, -y, or X,Y,Z with --look-at");
  if (glm::length(glm::vec3(v[0], v[1], v[2])) < 1e-6f) throw std::invalid_argument("'" + text + "': a zero vector");
}

render::DrawMode parseDraw(const std::string& text) {
  for (int i = 0; i < 3; ++i)
    if (text == render::kDrawModeNames[i]) return static_cast<render::DrawMode>(i);
  throw std::invalid_argument("'" + text + "': expected ellipsoids, centres or none");
}

// --slice LO:HI: heights above the floor in metres, LO < HI.
render::HeightSlice parseSlice(const std::string& text) {
  const std::size_t colon = text.find(':');
  const std::string form = "LO:HI (heights above the floor in metres, LO < HI)";
  if (colon == std::string::npos) throw std::invalid_argument("'" + text + "': expected " + form);
  const std::vector<float> lo = parseNumbers(text.substr(0, colon), 1, 1, form);
  const std::vector<float> hi = parseNumbers(text.substr(colon + 1), 1, 1, form);
  if (!(lo[0] < hi[0])) throw std::invalid_argument("'" + text + "': expected " + form);
  return {true, lo[0], hi[0]};
}

// The view keys of Settings that `spec` sets (the reverse of viewSpecOf), so --set can change them.
void copyView(const render::ViewSpec& spec, gui::Settings* s) {
  s->up_axis = spec.up;
  s->color = spec.color;
  s->show_ellipsoids = spec.ellipsoids;
  s->ellipsoid_sigma = spec.sigma;
  s->show_frustums = spec.layers.frustums;
  s->show_graph = spec.layers.graph;
  s->show_trajectory = spec.layers.trajectory;
  s->show_groundtruth = spec.layers.groundtruth;
  s->show_legend = spec.layers.legend;
  s->container_grid = spec.layers.grid;
  s->container_bounds = spec.layers.bounds;
  s->background = spec.background;
}

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

std::pair<int, int> parseViewSize(const std::string& text) {
  std::smatch m;
  static const std::regex pattern(R"((\d{1,9})x(\d{1,9}))");
  if (!std::regex_match(text, m, pattern))
    throw std::invalid_argument("'" + text + "': expected WIDTHxHEIGHT, e.g. 1280x720");
  const int w = std::stoi(m[1]), h = std::stoi(m[2]);
  if (w < 1 || h < 1 || w > render::kMaxImageSide || h > render::kMaxImageSide)
    throw std::invalid_argument("'" + text + "': each side must be in 1.." + std::to_string(render::kMaxImageSide));
  return {w, h};
}

void addRenderViewOptions(CLI::App& verb, RenderViewArgs& a) {
  verb.add_option("--view", a.view,
                  "global (map, frustums, covisibility edges coloured by weight, trajectory) | keyframe:K (the map "
                  "from keyframe K with its intrinsics) | container:K (K's image with its ellipses); default global")
      ->check(parsedBy([](const std::string& t) { render::ViewSpec s; parseViewName(t, &s); }, "VIEW"));
  verb.add_option("--size", a.size,
                  "image size WIDTHxHEIGHT (default: 1280x720 global, the camera's for keyframe:K, the "
                  "container's 2W x 2H for container:K)")
      ->check(parsedBy(parseViewSize, "WxH"));
  std::string color_modes;
  for (const char* name : render::kColorModeNames) color_modes += (color_modes.empty() ? "" : " | ") + std::string(name);
  verb.add_option("--color", a.color, color_modes + " (default rgb; uncertainty, count and keyframe draw a legend)")
      ->check(parsedBy(render::parseColorMode, "MODE"));
  verb.add_option("--background", a.background, "dark (the window's, the default) | white | #rrggbb")
      ->check(parsedBy(gui::parseBackground, "COLOUR"));
  verb.add_option("--layers", a.layers,
                  "what is drawn besides the map: none, or a comma-separated list of frustums, graph, trajectory, "
                  "groundtruth, legend, grid, bounds (default: all but grid, as the window)")
      ->check(parsedBy(parseLayers, "LIST"));
  verb.add_option("--up", a.up,
                  "the world's up axis: data (estimated from the cameras and the map's floor, the default) | +z | "
                  "+y | -y; with --look-at also the image's up vector X,Y,Z")
      ->check(parsedBy(checkUp, "UP"));
  verb.add_option("--draw", a.draw,
                  "ellipsoids (the default) | centres (the ellipsoid centres as points) | none (the map hidden; "
                  "trajectories and frustums still drawn)")
      ->check(parsedBy(parseDraw, "WHAT"));
  verb.add_option("--slice", a.slice,
                  "draw only the ellipsoids whose centre lies LO..HI metres above the floor (along the up axis; "
                  "the floor is the 2nd percentile of the map's heights)")
      ->check(parsedBy(parseSlice, "LO:HI"));
  auto* look = verb.add_option("--look-at", a.look_at,
                               "global view: the camera at EX,EY,EZ looking at TX,TY,TZ (world frame, metres; the "
                               "image's up from --up)")
                   ->check(parsedBy([](const std::string& t) { parseNumbers(t, 6, 6, "EX,EY,EZ,TX,TY,TZ"); },
                                    "EX,EY,EZ,TX,TY,TZ"));
  verb.add_option("--orbit", a.orbit,
                  "global view: the default view turned to AZ degrees about the up axis and EL above the horizon "
                  "(-60,35 is the default view), at DIST metres from the framed centre (default: framed)")
      ->check(parsedBy([](const std::string& t) { parseNumbers(t, 2, 3, "AZ,EL[,DIST]"); }, "AZ,EL[,DIST]"))
      ->excludes(look);
  verb.add_option("--fov", a.fov, "vertical field of view of the global view, degrees (default 60)")
      ->check(CLI::Range(1.f, 179.f));
  verb.add_option("--view-file", a.view_file,
                  "a view file (JSON, saved by the workbench's S key): its view, size, camera and options; flags "
                  "given beside it override it");
  verb.add_option("--settings", a.settings,
                  "a settings.json (its thresholds and view keys) or a view file (its thresholds) instead of the "
                  "defaults or the session's thresholds");
  verb.add_option("--set", a.set, "KEY=VALUE over every other source: " + gui::settingKeyList())
      ->allow_extra_args(false);
  verb.add_option("--sigma", a.sigma, "ellipsoid surface at this many standard deviations (default 2)")
      ->check(positiveFiniteCheck());
  verb.add_option("--sphere-level", a.sphere_level,
                  "icosphere subdivisions of one ellipsoid (0..3; default 0, icosahedra, as the window)")
      ->check(CLI::Range(0, 3));
  verb.add_option("--points-below", a.points_below,
                  "draw ellipsoids projecting to a radius below this many pixels as flat splats (0: never; default 4)")
      ->check(CLI::Range(0.f, 64.f));
  verb.add_option("--select", a.select, "draw keyframe K's frustum white, as the window's selection")
      ->check(CLI::Range(0, 1 << 30));
  verb.add_flag("--grid", a.grid, "container view: draw the cell grid (as --layers with grid)");
}

ResolvedView resolveViewSpec(const RenderViewArgs& a, const std::optional<GlobalMapParams>& session_thresholds) {
  ResolvedView out;
  gui::Settings settings;
  out.settings_source = "defaults";
  if (session_thresholds) {
    settings.thresholds = *session_thresholds;
    out.settings_source = "the session's thresholds";
  }
  bool view_keys_from_file = false;
  if (!a.settings.empty()) {
    view_keys_from_file = !isViewFile(a.settings);
    settings = readSettingsArg(a.settings, settings);
    out.settings_source = a.settings + (session_thresholds ? " over the session's thresholds" : "");
  }
  render::ViewSpec spec = view_keys_from_file ? gui::viewSpecOf(settings) : render::ViewSpec{};
  if (!a.view_file.empty()) spec = readViewFile(a.view_file);
  // Flags and --set, over everything else.
  if (!a.view.empty()) {
    const render::ViewSpec given = [&] {
      render::ViewSpec s;
      parseViewName(a.view, &s);
      return s;
    }();
    if (given.kind != spec.kind || given.keyframe != spec.keyframe) {
      spec.kind = given.kind;
      spec.keyframe = given.keyframe;
      if (a.size.empty()) spec.width = spec.height = 0;  // the new kind's default size
      spec.look_at.reset();
      spec.orbit.reset();
    }
  }
  if (!a.set.empty()) {
    copyView(spec, &settings);
    for (const std::string& kv : a.set) gui::applySetting(settings, kv);
    const render::ViewSpec from_set = gui::viewSpecOf(settings);
    spec.up = from_set.up;
    spec.color = from_set.color;
    spec.ellipsoids = from_set.ellipsoids;
    spec.sigma = from_set.sigma;
    spec.layers = from_set.layers;
    spec.background = from_set.background;
  }
  if (!a.size.empty()) std::tie(spec.width, spec.height) = parseViewSize(a.size);
  if (!a.color.empty()) spec.color = render::parseColorMode(a.color);
  if (!a.background.empty()) spec.background = gui::parseBackground(a.background);
  if (!a.layers.empty()) spec.layers = parseLayers(a.layers);
  if (a.grid) spec.layers.grid = true;
  if (!a.draw.empty()) spec.setDraw(parseDraw(a.draw));
  if (!a.slice.empty()) spec.slice = parseSlice(a.slice);
  if (a.sigma) spec.sigma = *a.sigma;
  if (a.sphere_level) spec.sphere_level = *a.sphere_level;
  if (a.points_below) spec.points_below_px = *a.points_below;
  if (a.select) spec.selected_keyframe = *a.select;
  if (a.fov) {
    spec.fov_y_deg = *a.fov;
    if (spec.look_at) spec.look_at->fov_y_deg = *a.fov;
  }
  std::optional<glm::vec3> up_vector;
  if (!a.up.empty()) {
    if (const auto axis = parseUpAxis(a.up)) spec.up = *axis;
    else {
      const std::vector<float> v = parseNumbers(a.up, 3, 3, "X,Y,Z");
      up_vector = glm::vec3(v[0], v[1], v[2]);
    }
  }
  if (!a.look_at.empty()) {
    const std::vector<float> v = parseNumbers(a.look_at, 6, 6, "EX,EY,EZ,TX,TY,TZ");
    render::LookAt look;
    look.eye = {v[0], v[1], v[2]};
    look.target = {v[3], v[4], v[5]};
    if (glm::length(look.eye - look.target) < 1e-6f)
      throw std::invalid_argument("--look-at " + a.look_at + ": the eye and the target must differ");
    look.fov_y_deg = spec.fov_y_deg;
    look.up = spec.look_at ? spec.look_at->up : glm::vec3(0.f);  // zero: the up axis, resolved when drawn
    spec.look_at = look;
    spec.orbit.reset();
  }
  if (up_vector) {
    if (!spec.look_at) throw std::invalid_argument("--up " + a.up + ": a vector needs --look-at (or a view file's camera)");
    spec.look_at->up = *up_vector;
  } else if (!a.up.empty() && spec.look_at && a.look_at.empty()) {
    spec.look_at->up = glm::vec3(0.f);  // an axis name: the view file's camera keeps up that axis
  }
  if (!a.orbit.empty()) {
    const std::vector<float> v = parseNumbers(a.orbit, 2, 3, "AZ,EL[,DIST]");
    render::Orbit orbit{v[0], v[1], std::nullopt};
    if (v.size() == 3) {
      if (!(v[2] > 0)) throw std::invalid_argument("--orbit " + a.orbit + ": DIST must be > 0");
      orbit.distance_m = v[2];
    }
    spec.orbit = orbit;
    spec.look_at.reset();
  }
  if ((spec.look_at || spec.orbit) && spec.kind != render::ViewKind::kGlobal)
    throw std::invalid_argument("--look-at and --orbit place the global view's camera; --view " + viewName(spec) +
                                " has its keyframe's");
  out.spec = spec;
  out.thresholds = settings.thresholds;
  return out;
}

const render::Gl& sharedOffscreenGl() {
  static std::unique_ptr<render::Context> context = render::createOffscreenContext();
  return context->gl();
}

namespace {

// Whether `path` is a map file loadStaticMap reads (a sequence folder, a typo and the rest: no,
// and they keep their own errors).
bool isStaticMapFile(const std::string& path) {
  try {
    const MapFileKind kind = detectMapFile(path);
    return kind != MapFileKind::kSequence && kind != MapFileKind::kSession && kind != MapFileKind::kViewFile;
  } catch (const InputError&) {
    return false;
  }
}

}  // namespace

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
  std::vector<Transform> map_cameras;  // a map folder's trajectory (else keyframes): the data up axis
  ColoredTriangleMesh mesh;
  std::vector<std::pair<std::vector<double>, GlobalMap>> maps;  // by paramsKey
  // The query slice (--query-slice): the point queries of the last map asked for, and the slice.
  std::optional<render::QuerySliceSpec> query_slice;
  const std::vector<Ellipsoid>* query_for = nullptr;
  std::shared_ptr<const QueryMap> query;
  std::shared_ptr<const render::QuerySliceImage> slice_image;
  render::HeightFrame slice_height;  // what slice_image was computed at
  std::unique_ptr<render::MapMirror> mirror;
  int mirror_level = -1;
  std::unique_ptr<render::MeshRenderer> mesh_renderer;
  int container_serial = 0;
  std::vector<Ellipsoid> sliced;  // the map's ellipsoids a --slice keeps
  int slice_serial = 0;
};

RenderSource::RenderSource(const SequenceArgs& sequence_in, const std::string& map_in, const std::string& mesh)
    : impl_(std::make_unique<Impl>()) {
  SequenceArgs sequence = sequence_in;
  std::string map = map_in;
  // A saved session or a map file can stand where SEQ does (as for vdmap gui) or be given as --map.
  if (!sequence.folder.empty() && (isSessionPath(sequence.folder) || isStaticMapFile(sequence.folder)))
    std::swap(map, sequence.folder);
  Impl& m = *impl_;
  if (!map.empty() && isSessionPath(map)) {
    m.session.emplace(loadSession(map, {.decode_images = false}));  // a container view decodes its keyframe's image
    m.graph = &m.session->graph;
    m.state = &m.session->info.state;
    m.camera = m.session->info.camera;
    m.cell_size_px = m.session->info.mapper.local_map.cell_size_px;
    m.frames = m.session->info.state.frames_mapped;
    m.tracked = m.session->info.mapper.poses == PoseSource::kTrack;
    name_ = map;
  } else if (!map.empty()) {
    // A map file (a `vdmap map` folder, an ellipsoid or point PLY, an OctoMap) is drawn by its
    // ellipsoids (mapping/export/map_file.h, as the workbench opens it).
    StaticMap file = loadStaticMap(map);
    // The cameras the window's data up axis uses too (the trajectory, else the keyframes).
    for (const StampedPose& p : file.trajectory.empty() ? file.keyframes : file.trajectory) m.map_cameras.push_back(p.T_W_C);
    m.map_file = std::move(file.ellipsoids);
    name_ = map;
  }
  if (!mesh.empty()) {
    m.mesh = readPlyMesh(mesh);
    if (name_.empty()) name_ = mesh;
  }
  if (!sequence.folder.empty()) {
    const TumSequence seq = openSequence(sequence);
    noteCameraGuess(seq, "render");
    MapperParams params;
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

std::size_t RenderSource::meshTriangles() const { return impl_->mesh.triangles.size(); }

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
  if (m.query_for != &map) {
    // The global map's point queries (docs/method.md 13): a map file has no keyframes, so its
    // queries hold the ellipsoids alone (nothing seen free).
    const GlobalMap* global = nullptr;
    for (const auto& entry : m.maps)
      if (&entry.second.ellipsoids == &map) global = &entry.second;
    GlobalMap file_map;
    if (!global) file_map.ellipsoids = map, global = &file_map;
    const KeyframeGraph none;
    m.query = std::make_shared<const QueryMap>(QueryMap::build(global == &file_map ? none : *m.graph, *global, QueryParams{}));
    m.query_for = &map;
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

const render::QuerySliceImage* RenderSource::lastQuerySlice() const { return impl_->slice_image.get(); }

glm::vec3 RenderSource::up(render::UpAxis axis, const GlobalMapParams& params) {
  if (axis != render::UpAxis::kData) return render::upDirection(axis, {}, {});
  std::vector<Transform> cameras;
  if (impl_->graph) cameras = render::graphSceneOf(*impl_->graph, *impl_->state, impl_->camera, false).trajectory;
  else cameras = impl_->map_cameras;
  return render::upDirection(axis, cameras, globalMap(params));
}

void RenderSource::checkView(const render::ViewSpec& spec) const {
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
                        {.sigma = spec.sigma, .color = spec.color, .cell_size_px = m.cell_size_px,
                         .show_grid = spec.layers.grid, .show_bounds = spec.layers.bounds});
    last_drawn_ = kept.size();
    return render::renderView(gl, mirror, spec, scene, w, h);
  }
  const std::vector<Ellipsoid>& map = globalMap(params);
  // The generation names the map in the cache (a new params key is a new generation).
  int generation = 1;
  for (std::size_t i = 0; i < m.maps.size(); ++i)
    if (&m.maps[i].second.ellipsoids == &map) generation = static_cast<int>(i) + 2;
  // Heights (colours, the slice) are measured from the whole map's floor along the view's up.
  scene.up = up(spec.up, params);
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
  render::GraphScene graph;
  if (m.graph) graph = render::graphSceneOf(*m.graph, *m.state, m.camera, m.tracked);
  graph.selected_keyframe = spec.selected_keyframe;
  mirror.setGraph(1, spec.selected_keyframe, [&] { return graph; });
  if (spec.kind == render::ViewKind::kKeyframe) {
    scene.T_W_K = m.graph->keyframe(spec.keyframe).T_W_K;
    graph.tracked = false;  // the window shows no tracking key through a keyframe
  }
  // The frame holds what is drawn: each ellipsoid's extent at the sigma (strays left out), and a
  // mesh whole.
  render::DrawnBounds drawn = render::drawnBounds(map, spec.sigma, spec.draw(), spec.slice, scene.height,
                                                  render::frameAxes(map, scene.up));
  for (const auto& p : m.mesh.positions) {
    const glm::vec3 q = glm::transpose(drawn.axes) * glm::vec3(p.x(), p.y(), p.z());
    drawn.lo = drawn.empty ? q : glm::min(drawn.lo, q);
    drawn.hi = drawn.empty ? q : glm::max(drawn.hi, q);
    drawn.empty = false;
  }
  last_strays_ = drawn.strays;
  scene.bounds = render::frameBounds(drawn, graph);
  if (spec.look_at && glm::length(spec.look_at->up) < 1e-6f) spec.look_at->up = scene.up;
  last_up_ = spec.look_at ? glm::normalize(spec.look_at->up) : scene.up;
  mirror.setLegend(spec.layers.legend ? render::legendFor(spec.color, mirror.mapColorRange(), graph,
                                                          spec.layers.trajectory, spec.layers.groundtruth,
                                                          spec.layers.graph)
                                      : render::Legend{},
                   spec.background, w);
  if (!m.mesh.triangles.empty() && !m.mesh_renderer) {
    m.mesh_renderer = std::make_unique<render::MeshRenderer>(gl);
    m.mesh_renderer->set(render::toColoredMesh(m.mesh));
  }
  last_drawn_ = spec.map_hidden ? 0 : shown->size();
  return render::renderView(gl, mirror, spec, scene, w, h, m.mesh_renderer.get());
}

}  // namespace vdmap::app
