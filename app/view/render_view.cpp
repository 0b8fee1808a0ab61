#include "app/view/render_view.h"

#include <algorithm>
#include <cmath>
#include <regex>

#include "app/cli/parameter_table.h"
#include "app/view/map_sequence.h"
#include "app/view/view_file.h"
#include "mapping/core/error.h"
#include "mapping/files/map_file.h"
#include "mapping/pipeline/parameters.h"
#include "render/colormap.h"
#include "render/context.h"
#include "render/map_mirror.h"
#include "render/map_scene.h"
#include "render/mesh_renderer.h"
#include "render/view_draw.h"

namespace vdmap::app {
namespace fs = std::filesystem;

namespace {

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
  for (bool render::ViewLayers::*f : render::kViewLayerFields) layers.*f = false;
  if (text == "none") return layers;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    bool known = false;
    for (std::size_t i = 0; i < std::size(render::kViewLayerNames); ++i)
      if (item == render::kViewLayerNames[i]) layers.*render::kViewLayerFields[i] = known = true;
    if (!known)
      throw std::invalid_argument("'" + item +
                                  "': expected none or a comma-separated list of frustums, graph, "
                                  "trajectory, groundtruth, legend, grid, bounds, mesh");
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
  const std::vector<float> v = parseNumbers(text, 3, 3, "data, +z, +y, -y, or X,Y,Z");
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
  s->up_vector = spec.up_vector;
  s->projection = spec.projection;
  s->rotation = spec.rotation;
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
  s->show_mesh = spec.layers.mesh;
  s->mesh_style = spec.mesh_style;
  s->background = spec.background;
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
      ->check(parsedBy(
          [](const std::string& t) {
            render::ViewSpec s;
            parseViewName(t, &s);
          },
          "VIEW"));
  verb.add_option("--size", a.size,
                  "image size WIDTHxHEIGHT (default: 1280x720 global, the camera's for keyframe:K, the "
                  "container's 2W x 2H for container:K)")
      ->check(parsedBy(parseViewSize, "WxH"));
  std::string color_modes;
  for (const char* name : render::kColorModeNames)
    color_modes += (color_modes.empty() ? "" : " | ") + std::string(name);
  verb.add_option("--color", a.color, color_modes + " (default rgb; uncertainty, count and keyframe draw a legend)")
      ->check(parsedBy(render::parseColorMode, "MODE"));
  verb.add_option("--background", a.background, "dark (the window's, the default) | white | #rrggbb")
      ->check(parsedBy(gui::parseBackground, "COLOUR"));
  verb.add_option("--layers", a.layers,
                  "what is drawn besides the map: none, or a comma-separated list of frustums, graph, trajectory, "
                  "groundtruth, legend, grid, bounds, mesh (the surface mesh of the local maps; default: all but "
                  "grid and mesh, as the window)")
      ->check(parsedBy(parseLayers, "LIST"));
  verb.add_option("--mesh-style", a.mesh_style,
                  "how the mesh layer is drawn: shaded (grey, lit; the default) | colour (its colours, lit) | "
                  "wireframe (its triangles' edges)")
      ->check(CLI::IsMember({render::kMeshStyleNames[0], render::kMeshStyleNames[1], render::kMeshStyleNames[2]}));
  addMeshOptions(verb, a.mesh);
  verb.add_option("--up", a.up,
                  "the world's up axis: data (estimated from the cameras and the map's floor, or a map file's level "
                  "planes; the default) | +z | +y | -y | a direction X,Y,Z; with --look-at, X,Y,Z is the image's up")
      ->check(parsedBy(checkUp, "UP"));
  verb.add_option("--projection", a.projection,
                  "perspective (the default) | orthographic (parallel rays; the scale at the target as the "
                  "perspective view's)")
      ->check(CLI::IsMember({render::kProjectionNames[0], render::kProjectionNames[1]}));
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
                  "a view file (JSON, saved by the workbench's Ctrl+S): its view, size, camera and options; flags "
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
    spec.up_vector = from_set.up_vector;
    spec.projection = from_set.projection;
    spec.rotation = from_set.rotation;
    spec.color = from_set.color;
    spec.ellipsoids = from_set.ellipsoids;
    spec.sigma = from_set.sigma;
    spec.layers = from_set.layers;
    spec.mesh_style = from_set.mesh_style;
    spec.background = from_set.background;
  }
  if (!a.size.empty()) std::tie(spec.width, spec.height) = parseViewSize(a.size);
  if (!a.color.empty()) spec.color = render::parseColorMode(a.color);
  if (!a.background.empty()) spec.background = gui::parseBackground(a.background);
  if (!a.layers.empty()) spec.layers = parseLayers(a.layers);
  if (a.grid) spec.layers.grid = true;
  if (!a.mesh_style.empty())
    spec.mesh_style = static_cast<render::MeshStyle>(
        std::find(std::begin(render::kMeshStyleNames), std::end(render::kMeshStyleNames), a.mesh_style) -
        std::begin(render::kMeshStyleNames));
  if (!a.draw.empty()) spec.setDraw(parseDraw(a.draw));
  if (!a.slice.empty()) spec.slice = parseSlice(a.slice);
  if (a.sigma) spec.sigma = *a.sigma;
  if (a.sphere_level) spec.sphere_level = *a.sphere_level;
  if (a.points_below) spec.points_below_px = *a.points_below;
  if (a.select) spec.selected_keyframe = *a.select;
  if (!a.projection.empty())
    spec.projection = a.projection == render::kProjectionNames[1] ? render::Projection::kOrthographic
                                                                  : render::Projection::kPerspective;
  if (a.fov) {
    spec.fov_y_deg = *a.fov;
    if (spec.look_at) spec.look_at->fov_y_deg = *a.fov;
  }
  std::optional<glm::vec3> up_vector;
  if (!a.up.empty()) {
    if (const auto axis = parseUpAxis(a.up)) {
      spec.up = *axis;
      spec.up_vector.reset();
    } else {
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
  if (up_vector && spec.look_at) {
    spec.look_at->up = *up_vector;
  } else if (up_vector) {
    spec.up_vector = *up_vector;  // the world's up, set by the user
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
  // Here a camera comes from a flag: a view file's camera with a keyframe's view is refused when read.
  if ((spec.look_at || spec.orbit) && spec.kind != render::ViewKind::kGlobal)
    throw std::invalid_argument(
        std::string(a.look_at.empty() ? "--orbit" : "--look-at") + " places the global view's camera; " +
        (a.view.empty() ? a.view_file + "'s view '" + viewName(spec) + "'" : "--view " + viewName(spec)) +
        " has its keyframe's");
  out.spec = spec;
  out.thresholds = settings.thresholds;
  out.mapper = settings.mapper;
  out.mesh = a.mesh.over(settings.mesh);
  return out;
}

}  // namespace vdmap::app
