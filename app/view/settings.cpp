#include "app/view/settings.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <sstream>

#include <nlohmann/json.hpp>

#include "app/cli/mesh_options.h"
#include "app/cli/parameter_table.h"
#include "app/view/json_file.h"
#include "mapping/core/atomic_file.h"
#include "mapping/core/error.h"
#include "mapping/io/json_text.h"
#include "mapping/io/text_list.h"
#include "render/colormap.h"

namespace vdmap::app::gui {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// The settings file's sections whose keys --set takes.
constexpr const char* kSetSections[] = {"thresholds", "rerun", "view"};

ParameterValues paramsOf(const Settings& s) { return {s.mapper, s.thresholds}; }

const char* sectionOf(const Parameter& p) { return p.live ? "thresholds" : "rerun"; }

// A settings-file value as the text parseValue reads (numbers, booleans and names as they are);
// anything else (an array, an object, null) is refused naming the key.
std::string valueText(const Parameter& p, const json& v) {
  if (v.is_string()) {
    if (p.kind == Parameter::Kind::kChoice) return v.get<std::string>();
    throw std::invalid_argument(std::string(p.key) + ": expected " +
                                (p.kind == Parameter::Kind::kBool ? "true or false" : "a number") + ", got '" +
                                v.get<std::string>() + "'");
  }
  if (v.is_boolean() || v.is_number()) return v.dump();
  throw std::invalid_argument(std::string(p.key) + ": expected " + validityText(p) + ", got " + v.dump());
}

// The query slice's plane as --query-slice writes it ("up=1", "x=-0.5").
std::string querySliceAt(const render::QuerySliceSpec& spec) {
  std::ostringstream out;
  out << render::querySliceAxisName(spec.axis) << "=" << std::setprecision(10) << spec.offset_m;
  return out.str();
}

json toJson(const Settings& s) {
  const ParameterValues params = paramsOf(s);
  json j = {
      {"thresholds", json::object()},
      {"rerun", json::object()},
      {"view",
       {{"color", render::colorModeName(s.color)},
        {"show_ellipsoids", s.show_ellipsoids},
        {"show_frustums", s.show_frustums},
        {"show_graph", s.show_graph},
        {"show_trajectory", s.show_trajectory},
        {"show_groundtruth", s.show_groundtruth},
        {"ellipsoid_sigma", s.ellipsoid_sigma},
        {"play_fps", s.play_fps},
        {"up_axis", kUpAxisNames[static_cast<int>(s.up_axis)]},
        {"up_vector", s.up_vector ? json::array({s.up_vector->x, s.up_vector->y, s.up_vector->z}) : json(nullptr)},
        {"projection", render::kProjectionNames[static_cast<int>(s.projection)]},
        {"rotation", render::kRotationNames[static_cast<int>(s.rotation)]},
        {"container_grid", s.container_grid},
        {"container_bounds", s.container_bounds},
        {"background", backgroundName(s.background)},
        {"show_legend", s.show_legend},
        {"show_mesh", s.show_mesh},
        {"mesh_style", render::kMeshStyleNames[static_cast<int>(s.mesh_style)]},
        {"mesh_max_slope", s.mesh.max_slope_deg},
        {"mesh_edge_sigma", s.mesh.edge_sigma},
        {"mesh_stride", s.mesh.stride},
        {"mesh_fuse", s.mesh.fuse},
        {"slice", s.slice.on},
        {"slice_lo", s.slice.lo_m},
        {"slice_hi", s.slice.hi_m},
        {"probe", s.probe},
        {"probe_offset", s.probe_offset_m},
        {"query_slice", s.query_slice},
        {"query_slice_at", querySliceAt(s.query_slice_spec)},
        {"query_slice_color", render::querySliceColorName(s.query_slice_spec.color)},
        {"query_slice_max_distance", s.query_slice_spec.max_distance_m}}},
      {"window", {{"width", s.window_width}, {"height", s.window_height}}},
      {"last_sequence", s.last_sequence},
      {"recent", s.recent},  // opened paths, newest first (Settings::recent)
  };
  for (const Parameter& p : parameters()) j[sectionOf(p)][std::string(p.key)] = valueJson(p, p.get(params));
  return j;
}

// Copies section[key] into `out` when present; a value of the wrong type is refused naming it.
template <typename T>
void read(const json& section, const char* section_name, const char* key, T& out) {
  if (!section.contains(key)) return;
  try {
    out = section.at(key).get<T>();
  } catch (const json::exception&) {
    const char* expected = std::is_same_v<T, bool>   ? "true or false"
                           : std::is_arithmetic_v<T> ? "a number"
                                                     : "a string";
    throw std::invalid_argument(std::string(section_name) + "." + key + ": expected " + expected + ", got " +
                                section.at(key).dump());
  }
}

// The index of `name` in `names`; throws naming the key and the accepted names.
template <std::size_t N>
int nameIndex(const char* const (&names)[N], const std::string& name, const char* key) {
  for (std::size_t i = 0; i < N; ++i)
    if (name == names[i]) return static_cast<int>(i);
  std::string list;
  for (const char* n : names) list += (list.empty() ? "" : " or ") + std::string(n);
  throw std::invalid_argument(std::string(key) + " must be " + list + ", got '" + name + "'");
}

// The view keys of the point queries: probe, probe_offset and the query slice's.
void readQueries(const json& v, Settings& s) {
  read(v, "view", "probe", s.probe);
  read(v, "view", "probe_offset", s.probe_offset_m);
  if (!(s.probe_offset_m >= 0.f && s.probe_offset_m <= 10.f))
    throw std::invalid_argument("view.probe_offset must be in [0, 10] m");
  read(v, "view", "query_slice", s.query_slice);
  render::QuerySliceSpec spec = s.query_slice_spec;
  std::string at = querySliceAt(spec), color = render::querySliceColorName(spec.color);
  read(v, "view", "query_slice_at", at);
  read(v, "view", "query_slice_color", color);
  read(v, "view", "query_slice_max_distance", spec.max_distance_m);
  try {
    const render::QuerySliceSpec plane = render::parseQuerySlice(at);
    spec.axis = plane.axis, spec.offset_m = plane.offset_m;
    spec.color = render::parseQuerySliceColor(color);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("view.query_slice_at / query_slice_color: ") + e.what());
  }
  if (!(spec.max_distance_m > 0.0 && spec.max_distance_m <= 100.0))
    throw std::invalid_argument("view.query_slice_max_distance must be in (0, 100] m");
  s.query_slice_spec = spec;
}

// The view keys of how the mesh is made, checked as `vdmap mesh` checks its options.
void readMesh(const json& v, MeshParams& mesh) {
  read(v, "view", "mesh_max_slope", mesh.max_slope_deg);
  read(v, "view", "mesh_edge_sigma", mesh.edge_sigma);
  read(v, "view", "mesh_stride", mesh.stride);
  read(v, "view", "mesh_fuse", mesh.fuse);
  if (!(mesh.max_slope_deg >= 0.0 && mesh.max_slope_deg <= kMeshMaxSlopeDeg))
    throw std::invalid_argument("view.mesh_max_slope must be in [0, " + CLI::detail::to_string(kMeshMaxSlopeDeg) +
                                "] degrees");
  if (!(mesh.edge_sigma >= 0.0 && mesh.edge_sigma <= kMeshMaxEdgeSigma))
    throw std::invalid_argument("view.mesh_edge_sigma must be in [0, " + CLI::detail::to_string(kMeshMaxEdgeSigma) +
                                "]");
  if (mesh.stride < 1 || mesh.stride > kMeshMaxStride)
    throw std::invalid_argument("view.mesh_stride must be in 1.." + std::to_string(kMeshMaxStride));
}

// The view keys up_vector (null or [x, y, z], not zero), projection and rotation.
void readViewCamera(const json& v, Settings& s) {
  if (v.contains("up_vector")) {
    const json& u = v.at("up_vector");
    s.up_vector.reset();
    if (!u.is_null()) {
      if (!u.is_array() || u.size() != 3 ||
          !std::all_of(u.begin(), u.end(), [](const json& x) { return x.is_number(); }))
        throw std::invalid_argument("view.up_vector: expected null or [x, y, z], got " + u.dump());
      const glm::vec3 up(u[0].get<float>(), u[1].get<float>(), u[2].get<float>());
      if (!(glm::length(up) > 1e-6f) || !std::isfinite(glm::length(up)))
        throw std::invalid_argument("view.up_vector must be a finite, non-zero vector, got " + u.dump());
      s.up_vector = up;
    }
  }
  std::string projection = render::kProjectionNames[static_cast<int>(s.projection)];
  read(v, "view", "projection", projection);
  s.projection = static_cast<render::Projection>(nameIndex(render::kProjectionNames, projection, "view.projection"));
  std::string rotation = render::kRotationNames[static_cast<int>(s.rotation)];
  read(v, "view", "rotation", rotation);
  s.rotation = static_cast<render::Rotation>(nameIndex(render::kRotationNames, rotation, "view.rotation"));
}

Settings fromJson(const json& j, const Settings& base = {}) {
  Settings s = base;
  if (!j.is_object()) throw std::invalid_argument("expected a JSON object");
  refuseUnknownKeys(j, toJson(Settings{}));  // a misspelt key or section is named, never ignored
  // The mapping parameters, each read and checked by the parameter table (as --set and the
  // command line do).
  ParameterValues params = paramsOf(s);
  for (const Parameter& p : parameters()) {
    const char* section = sectionOf(p);
    if (!j.contains(section) || !j.at(section).contains(p.key)) continue;
    try {
      setFromText(p, params, valueText(p, j.at(section).at(std::string(p.key))));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string(section) + "." + e.what());
    }
  }
  validate(params);
  s.mapper = params.mapper;
  s.thresholds = params.global;
  if (j.contains("view")) {
    const json& v = j.at("view");
    std::string color = render::colorModeName(s.color), up = kUpAxisNames[static_cast<int>(s.up_axis)];
    read(v, "view", "color", color);
    s.color = render::parseColorMode(color);
    read(v, "view", "show_ellipsoids", s.show_ellipsoids);
    read(v, "view", "show_frustums", s.show_frustums);
    read(v, "view", "show_graph", s.show_graph);
    read(v, "view", "show_trajectory", s.show_trajectory);
    read(v, "view", "show_groundtruth", s.show_groundtruth);
    read(v, "view", "ellipsoid_sigma", s.ellipsoid_sigma);
    read(v, "view", "play_fps", s.play_fps);
    read(v, "view", "up_axis", up);
    const auto it = std::find(std::begin(kUpAxisNames), std::end(kUpAxisNames), up);
    if (it == std::end(kUpAxisNames))
      throw std::invalid_argument("view.up_axis must be data, +z, +y or -y, got '" + up + "'");
    s.up_axis = static_cast<UpAxis>(it - std::begin(kUpAxisNames));
    readViewCamera(v, s);
    read(v, "view", "container_grid", s.container_grid);
    read(v, "view", "container_bounds", s.container_bounds);
    std::string background = backgroundName(s.background);
    read(v, "view", "background", background);
    try {
      s.background = parseBackground(background);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(std::string("view.background: ") + e.what());
    }
    read(v, "view", "show_legend", s.show_legend);
    read(v, "view", "show_mesh", s.show_mesh);
    std::string mesh_style = render::kMeshStyleNames[static_cast<int>(s.mesh_style)];
    read(v, "view", "mesh_style", mesh_style);
    s.mesh_style = static_cast<render::MeshStyle>(nameIndex(render::kMeshStyleNames, mesh_style, "view.mesh_style"));
    readMesh(v, s.mesh);
    read(v, "view", "slice", s.slice.on);
    read(v, "view", "slice_lo", s.slice.lo_m);
    read(v, "view", "slice_hi", s.slice.hi_m);
    if (!(s.slice.lo_m < s.slice.hi_m && s.slice.lo_m >= -1e4f && s.slice.hi_m <= 1e4f))
      throw std::invalid_argument("view.slice_lo must be below view.slice_hi (metres above the floor, within 1e4)");
    readQueries(v, s);
    if (!(s.ellipsoid_sigma > 0 && s.ellipsoid_sigma <= 10))
      throw std::invalid_argument("view.ellipsoid_sigma must be in (0, 10]");
    if (!(s.play_fps >= 0 && s.play_fps <= 1000)) throw std::invalid_argument("view.play_fps must be in [0, 1000]");
  }
  if (j.contains("window")) {
    read(j.at("window"), "window", "width", s.window_width);
    read(j.at("window"), "window", "height", s.window_height);
    if (s.window_width < 320 || s.window_height < 240 || s.window_width > 16384 || s.window_height > 16384)
      throw std::invalid_argument("window size must be in 320x240..16384x16384");
  }
  read(j, "settings", "last_sequence", s.last_sequence);
  // Recently opened paths: a list of strings, the newest kRecentFiles kept.
  if (j.contains("recent")) {
    const json& r = j.at("recent");
    if (!r.is_array() || !std::all_of(r.begin(), r.end(), [](const json& v) { return v.is_string(); }))
      throw std::invalid_argument("recent: expected a list of paths, got " + r.dump());
    s.recent.clear();
    for (const json& v : r)
      if (s.recent.size() < kRecentFiles) s.recent.push_back(v.get<std::string>());
  }
  return s;
}

}  // namespace

glm::vec3 parseBackground(const std::string& text) {
  if (text == "dark") return render::kDarkBackground;
  if (text == "white") return render::kWhiteBackground;
  const auto hex = [](char c) -> int {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
  };
  if (text.size() == 7 && text[0] == '#') {
    glm::vec3 rgb;
    bool ok = true;
    for (int k = 0; k < 3; ++k) {
      const int hi = hex(text[1 + 2 * k]), lo = hex(text[2 + 2 * k]);
      ok = ok && hi >= 0 && lo >= 0;
      rgb[k] = static_cast<float>(hi * 16 + lo) / 255.f;
    }
    if (ok) return rgb;
  }
  throw std::invalid_argument("'" + text + "': expected dark, white or #rrggbb");
}

std::string backgroundName(const glm::vec3& rgb) {
  if (rgb == render::kDarkBackground) return "dark";
  if (rgb == render::kWhiteBackground) return "white";
  char text[8];
  const auto byte = [](float v) { return static_cast<int>(std::clamp(v, 0.f, 1.f) * 255.f + 0.5f); };
  std::snprintf(text, sizeof text, "#%02x%02x%02x", byte(rgb.r), byte(rgb.g), byte(rgb.b));
  return text;
}

render::ViewSpec viewSpecOf(const Settings& s) {
  render::ViewSpec spec;
  spec.up = s.up_axis;
  spec.up_vector = s.up_vector;
  spec.projection = s.projection;
  spec.rotation = s.rotation;
  spec.color = s.color;
  spec.ellipsoids = s.show_ellipsoids;
  spec.map_hidden = s.hide_map;
  spec.sigma = s.ellipsoid_sigma;
  spec.layers.frustums = s.show_frustums;
  spec.layers.graph = s.show_graph;
  spec.layers.trajectory = s.show_trajectory;
  spec.layers.groundtruth = s.show_groundtruth;
  spec.layers.legend = s.show_legend;
  spec.layers.grid = s.container_grid;
  spec.layers.bounds = s.container_bounds;
  spec.layers.mesh = s.show_mesh;
  spec.mesh_style = s.mesh_style;
  spec.slice = s.slice;
  spec.background = s.background;
  return spec;
}

Settings readSettingsFile(const fs::path& file, const Settings& base) {
  if (!fs::exists(file)) throw InputError(file.string(), "no such file");
  const json j = parseJsonStrictly(readWholeFile(file), file.string());
  try {
    return fromJson(j, base);
  } catch (const std::exception& e) {
    throw InputError(file.string(), e.what());
  }
}

fs::path settingsPath() {
  const char* xdg = std::getenv("XDG_CONFIG_HOME");
  const char* home = std::getenv("HOME");
  const fs::path base = xdg && *xdg ? fs::path(xdg) : fs::path(home && *home ? home : ".") / ".config";
  return base / "vdmap" / "settings.json";
}

Settings loadSettings(const fs::path& file, std::string* warning) {
  if (!fs::exists(file)) return {};
  try {
    return fromJson(parseJsonStrictly(readWholeFile(file), file.string()));
  } catch (const InputError& e) {  // names the file (and line) already
    if (warning) *warning = std::string(e.what()) + "; using the default settings";
    return {};
  } catch (const std::exception& e) {
    if (warning) *warning = file.string() + ": " + e.what() + "; using the default settings";
    return {};
  }
}

void saveSettings(const fs::path& file, const Settings& settings) {
  fs::create_directories(file.parent_path());
  writeFileAtomically(file, jsonText(toJson(settings)) + "\n");
}

void saveChangedSettings(const fs::path& file, const Settings& before, const Settings& after) {
  const json start = toJson(before), end = toJson(after);
  if (start == end) return;
  json saved = json::object();
  if (fs::exists(file)) {
    try {
      saved = parseJsonStrictly(readWholeFile(file), file.string());
      fromJson(saved);  // the same checks as loading
    } catch (const std::exception& e) {
      throw std::runtime_error(file.string() + " is not valid settings (" + e.what() +
                               "); left as it is, repair or delete it to save settings again");
    }
  }
  for (const auto& [section, values] : end.items()) {
    if (!values.is_object()) {
      if (values != start.at(section)) saved[section] = values;
      continue;
    }
    for (const auto& [key, value] : values.items())
      if (value != start.at(section).at(key)) saved[section][key] = value;
  }
  fs::create_directories(file.parent_path());
  writeFileAtomically(file, jsonText(saved) + "\n");
}

bool sameSettings(const Settings& a, const Settings& b) { return toJson(a) == toJson(b); }

bool rerunParamsDiffer(const Settings& a, const Settings& b) { return toJson(a).at("rerun") != toJson(b).at("rerun"); }

void addRecent(Settings& settings, const std::string& path) {
  std::vector<std::string>& r = settings.recent;
  r.erase(std::remove(r.begin(), r.end(), path), r.end());
  r.insert(r.begin(), path);
  if (r.size() > kRecentFiles) r.resize(kRecentFiles);
}

std::string settingKeyList() {
  const json defaults = toJson(Settings{});
  std::string list;
  for (const char* section : kSetSections) {
    list += std::string(list.empty() ? "" : "; ") + section + ":";
    for (const auto& [key, value] : defaults.at(section).items()) list += (list.back() == ':' ? " " : ", ") + key;
  }
  return list;
}

void applySetting(Settings& settings, const std::string& key_value) {
  const auto eq = key_value.find('=');
  if (eq == std::string::npos) throw std::invalid_argument("--set '" + key_value + "': expected KEY=VALUE");
  const std::string key = key_value.substr(0, eq), value = key_value.substr(eq + 1);
  try {
    if (const Parameter* p = findParameter(key)) {  // a mapping parameter: the table's check
      ParameterValues params = paramsOf(settings);
      setFromText(*p, params, value);
      validate(params);
      settings.mapper = params.mapper;
      settings.thresholds = params.global;
      return;
    }
    // A view key: through the settings file's reader, so both accept and check the same.
    json j = toJson(settings);
    if (!j["view"].contains(key)) throw std::invalid_argument("unknown key (see vdmap gui --help)");
    const json parsed = json::parse(value, nullptr, false);
    j["view"][key] = parsed.is_discarded() ? json(value) : parsed;
    settings = fromJson(j);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("--set '" + key_value + "': " + e.what());
  }
}

void refuseRemapSettings(const std::vector<std::string>& set, const std::string& what) {
  for (const std::string& kv : set) {
    const Parameter* p = findParameter(kv.substr(0, kv.find('=')));
    if (p && !p->live)
      throw std::invalid_argument("--set '" + kv + "': " + std::string(p->key) +
                                  " changes how frames are mapped, and " + what +
                                  " is mapped already (give its sequence to map it again)");
  }
}

}  // namespace vdmap::app::gui
