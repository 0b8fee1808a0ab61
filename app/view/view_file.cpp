#include "app/view/view_file.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <regex>
#include <set>

#include <nlohmann/json.hpp>

#include "app/cli/parameter_table.h"
#include "app/view/json_file.h"
#include "mapping/core/atomic_file.h"
#include "mapping/core/error.h"
#include "mapping/io/json_text.h"
#include "mapping/io/text_list.h"
#include "render/colormap.h"

namespace vdmap::app {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// 2 added "slice", 3 the optional "projection", "rotation", "up_vector", "mesh_style" and
// "layers.mesh" (the last two written only when the mesh is asked for); older files still read.
constexpr int kVersion = 3;
// What a number too large for a double (1e999) is replaced by before parsing, so that the reader
// can name its key ("must be finite") rather than the parser refuse the whole file.
const std::string kNonFinite = std::string("\x01non-finite");

// The text with every number literal outside strings that is not finite as a double replaced
// by the string kNonFinite.
std::string markNonFinite(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      out += c;
      if (c == '\\' && i + 1 < text.size()) out += text[++i];
      else if (c == '"') in_string = false;
      continue;
    }
    if (c == '"') in_string = true;
    if (c == '-' || (c >= '0' && c <= '9')) {
      std::size_t end = i;
      while (end < text.size() && std::strchr("+-0123456789.eE", text[end])) ++end;
      const std::string token = text.substr(i, end - i);
      if (!std::isfinite(std::strtod(token.c_str(), nullptr))) {
        out += json(kNonFinite).dump();
        i = end - 1;
        continue;
      }
    }
    out += c;
  }
  return out;
}
// The strict reader: every key of an object must be read, and nothing else may be there.
struct Reader {
  std::string path;  // "camera.eye" for messages

  [[noreturn]] static void fail(const std::string& what) { throw std::invalid_argument(what); }

  static const json& key(const json& object, const std::string& prefix, const char* name) {
    if (!object.contains(name)) fail("missing key '" + prefix + name + "'");
    return object.at(name);
  }
  static void onlyKeys(const json& object, const std::string& prefix, std::initializer_list<const char*> names) {
    for (const auto& [k, v] : object.items()) {
      bool known = false;
      std::string valid;
      for (const char* n : names) {
        known = known || k == n;
        valid += (valid.empty() ? "" : ", ") + std::string(n);
      }
      if (!known) fail("unknown key '" + prefix + k + "' (valid: " + valid + ")");
    }
  }
  static double number(const json& v, const std::string& name) {
    if (v.is_string() && v.get<std::string>() == kNonFinite) fail(name + " must be finite");
    if (!v.is_number()) fail(name + " must be a number, got " + v.dump());
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(name + " must be finite");
    return x;
  }
  static double number(const json& v, const std::string& name, double lo, double hi) {
    const double x = number(v, name);
    if (x < lo || x > hi) {
      char range[64];
      std::snprintf(range, sizeof range, "[%g, %g]", lo, hi);
      fail(name + " must be in " + range + ", got " + v.dump());
    }
    return x;
  }
  static int integer(const json& v, const std::string& name, int lo, int hi) {
    const double x = number(v, name, lo, hi);
    if (x != std::floor(x)) fail(name + " must be an integer, got " + v.dump());
    return static_cast<int>(x);
  }
  static bool boolean(const json& v, const std::string& name) {
    if (!v.is_boolean()) fail(name + " must be true or false, got " + v.dump());
    return v.get<bool>();
  }
  static std::string string(const json& v, const std::string& name) {
    if (!v.is_string()) fail(name + " must be a string, got " + v.dump());
    return v.get<std::string>();
  }
  // The index of the string `v` in `names`.
  template <std::size_t N>
  static int name(const json& v, const std::string& key, const char* const (&names)[N], const std::string& forms) {
    const std::string text = string(v, key);
    for (std::size_t i = 0; i < N; ++i)
      if (text == names[i]) return static_cast<int>(i);
    fail(key + " must be " + forms + ", got '" + text + "'");
  }
  static glm::vec3 vec3(const json& v, const std::string& name) {
    if (!v.is_array() || v.size() != 3) fail(name + " must be [x, y, z], got " + v.dump());
    glm::vec3 out;
    for (int k = 0; k < 3; ++k) out[k] = static_cast<float>(number(v[k], name + "[" + std::to_string(k) + "]"));
    return out;
  }
};

json vec3Json(const glm::vec3& v) { return json::array({v.x, v.y, v.z}); }

render::ViewSpec specFromJson(const json& j, GlobalMapParams* thresholds) {
  using R = Reader;
  if (!j.is_object()) R::fail("expected a JSON object (a view file)");
  const int version = R::integer(R::key(j, "", "vdmap_view"), "vdmap_view", 1, 1000);
  if (version > kVersion)
    R::fail("vdmap_view " + j.at("vdmap_view").dump() + ": this vdmap reads versions 1 to " + std::to_string(kVersion));
  if (version == 1)
    R::onlyKeys(j, "",
                {"vdmap_view", "source", "view", "size", "camera", "up_axis", "color", "draw", "sigma", "sphere_level",
                 "points_below_px", "background", "layers", "selected_keyframe", "thresholds"});
  else if (version == 2)
    R::onlyKeys(j, "",
                {"vdmap_view", "source", "view", "size", "camera", "up_axis", "color", "draw", "sigma", "sphere_level",
                 "points_below_px", "background", "layers", "selected_keyframe", "thresholds", "slice"});
  else
    R::onlyKeys(j, "",
                {"vdmap_view",
                 "source",
                 "view",
                 "size",
                 "camera",
                 "up_axis",
                 "color",
                 "draw",
                 "sigma",
                 "sphere_level",
                 "points_below_px",
                 "background",
                 "layers",
                 "selected_keyframe",
                 "thresholds",
                 "slice",
                 "projection",
                 "rotation",
                 "up_vector",
                 "mesh_style"});
  R::string(R::key(j, "", "source"), "source");
  render::ViewSpec spec;
  try {
    parseViewName(R::string(R::key(j, "", "view"), "view"), &spec);
  } catch (const std::invalid_argument& e) {
    R::fail(std::string("view: ") + e.what());
  }
  const json& size = R::key(j, "", "size");
  if (!size.is_array() || size.size() != 2) R::fail("size must be [W, H], got " + size.dump());
  // [0, 0]: the view kind's default size.
  spec.width = R::integer(size[0], "size[0]", 0, 16384);
  spec.height = R::integer(size[1], "size[1]", 0, 16384);
  if ((spec.width == 0) != (spec.height == 0))
    R::fail("size must be [W, H] with both > 0, or [0, 0], got " + size.dump());
  const json& camera = R::key(j, "", "camera");
  if (!camera.is_null()) {
    if (!camera.is_object()) R::fail("camera must be an object or null, got " + camera.dump());
    R::onlyKeys(camera, "camera.", {"eye", "target", "up", "fov_y_deg"});
    render::LookAt look;
    look.eye = R::vec3(R::key(camera, "camera.", "eye"), "camera.eye");
    look.target = R::vec3(R::key(camera, "camera.", "target"), "camera.target");
    look.up = R::vec3(R::key(camera, "camera.", "up"), "camera.up");
    look.fov_y_deg = static_cast<float>(R::number(R::key(camera, "camera.", "fov_y_deg"), "camera.fov_y_deg", 1, 179));
    if (glm::length(look.eye - look.target) < 1e-6f) R::fail("camera.eye and camera.target must differ");
    if (glm::length(look.up) < 1e-6f) R::fail("camera.up must not be zero");
    spec.look_at = look;
    spec.fov_y_deg = look.fov_y_deg;
    if (spec.kind != render::ViewKind::kGlobal)
      R::fail("'camera' places the global view, but 'view' is '" + viewName(spec) +
              "' (a keyframe's view has its keyframe's camera): set 'camera' to null or 'view' to 'global'");
  }
  const std::string up = R::string(R::key(j, "", "up_axis"), "up_axis");
  const auto it = std::find(std::begin(render::kUpAxisNames), std::end(render::kUpAxisNames), up);
  if (it == std::end(render::kUpAxisNames)) R::fail("up_axis must be data, +z, +y or -y, got '" + up + "'");
  spec.up = static_cast<render::UpAxis>(it - std::begin(render::kUpAxisNames));
  // Version 3's optional keys: absent, the defaults (perspective, orbit, the up axis).
  if (j.contains("up_vector") && !j.at("up_vector").is_null()) {
    spec.up_vector = R::vec3(j.at("up_vector"), "up_vector");
    if (glm::length(*spec.up_vector) < 1e-6f) R::fail("up_vector must not be zero");
  }
  if (j.contains("projection"))
    spec.projection = static_cast<render::Projection>(
        R::name(j.at("projection"), "projection", render::kProjectionNames, "perspective or orthographic"));
  if (j.contains("rotation"))
    spec.rotation = static_cast<render::Rotation>(
        R::name(j.at("rotation"), "rotation", render::kRotationNames, "orbit or trackball"));
  if (j.contains("mesh_style"))
    spec.mesh_style = static_cast<render::MeshStyle>(
        R::name(j.at("mesh_style"), "mesh_style", render::kMeshStyleNames, "shaded, colour or wireframe"));
  try {
    spec.color = render::parseColorMode(R::string(R::key(j, "", "color"), "color"));
  } catch (const std::invalid_argument& e) {
    R::fail(std::string("color: ") + e.what());
  }
  const std::string draw = R::string(R::key(j, "", "draw"), "draw");
  const auto mode = std::find(std::begin(render::kDrawModeNames), std::end(render::kDrawModeNames), draw);
  if (mode == std::end(render::kDrawModeNames)) R::fail("draw must be ellipsoids, centres or none, got '" + draw + "'");
  spec.setDraw(static_cast<render::DrawMode>(mode - std::begin(render::kDrawModeNames)));
  if (version >= 2) {
    // "slice": null (off) or [lo, hi], heights above the floor in metres.
    const json& slice = R::key(j, "", "slice");
    if (!slice.is_null()) {
      if (!slice.is_array() || slice.size() != 2) R::fail("slice must be null or [lo, hi], got " + slice.dump());
      spec.slice.on = true;
      spec.slice.lo_m = static_cast<float>(R::number(slice[0], "slice[0]", -1e4, 1e4));
      spec.slice.hi_m = static_cast<float>(R::number(slice[1], "slice[1]", -1e4, 1e4));
      if (!(spec.slice.lo_m < spec.slice.hi_m)) R::fail("slice must be [lo, hi] with lo < hi, got " + slice.dump());
    }
  }
  spec.sigma = static_cast<float>(R::number(R::key(j, "", "sigma"), "sigma", 1e-3, 10));
  if (!(spec.sigma > 0)) R::fail("sigma must be > 0");
  spec.sphere_level = R::integer(R::key(j, "", "sphere_level"), "sphere_level", 0, 3);
  spec.points_below_px = static_cast<float>(R::number(R::key(j, "", "points_below_px"), "points_below_px", 0, 64));
  try {
    spec.background = gui::parseBackground(R::string(R::key(j, "", "background"), "background"));
  } catch (const std::invalid_argument& e) {
    R::fail(std::string("background: ") + e.what());
  }
  const json& layers = R::key(j, "", "layers");
  if (!layers.is_object()) R::fail("layers must be an object, got " + layers.dump());
  R::onlyKeys(layers, "layers.",
              {"frustums", "graph", "trajectory", "groundtruth", "legend", "grid", "bounds", "mesh"});
  for (std::size_t i = 0; i < std::size(render::kViewLayerNames); ++i) {
    const std::string name = render::kViewLayerNames[i];
    if (name == "mesh" && !layers.contains(name)) continue;  // optional: off
    spec.layers.*render::kViewLayerFields[i] = R::boolean(R::key(layers, "layers.", name.c_str()), "layers." + name);
  }
  spec.selected_keyframe = R::integer(R::key(j, "", "selected_keyframe"), "selected_keyframe", -1, 1 << 30);
  const json& t = R::key(j, "", "thresholds");
  if (!t.is_object()) R::fail("thresholds must be an object, got " + t.dump());
  ParameterValues params;
  std::set<std::string> live;
  for (const Parameter& p : parameters()) {
    if (!p.live) continue;
    live.insert(std::string(p.key));
    const std::string name = "thresholds." + std::string(p.key);
    const json& v = R::key(t, "thresholds.", std::string(p.key).c_str());
    if ((v.is_number() && !std::isfinite(v.get<double>())) || (v.is_string() && v.get<std::string>() == kNonFinite))
      R::fail(name + " must be finite");
    if (!v.is_number() && !v.is_boolean() && !v.is_string()) R::fail(name + ": expected a value, got " + v.dump());
    try {
      setFromText(p, params, v.is_string() ? v.get<std::string>() : v.dump());
    } catch (const std::invalid_argument& e) {
      R::fail(std::string("thresholds.") + e.what());
    }
  }
  for (const auto& [k, v] : t.items())
    if (!live.count(k)) {
      std::string valid;
      for (const std::string& key : live) valid += (valid.empty() ? "" : ", ") + key;
      R::fail("unknown key 'thresholds." + k + "' (valid: " + valid + ")");
    }
  validate(params);
  if (thresholds) *thresholds = params.global;
  return spec;
}

json parseFile(const fs::path& file) {
  if (!fs::exists(file)) throw InputError(file.string(), "no such file");
  const std::string text = readWholeFile(file);
  return parseJsonStrictly(markNonFinite(text), file.string());
}

std::string number(float v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", v);  // round-trips a float exactly
  return text;
}

}  // namespace

std::string viewName(const render::ViewSpec& spec) {
  switch (spec.kind) {
    case render::ViewKind::kKeyframe: return "keyframe:" + std::to_string(spec.keyframe);
    case render::ViewKind::kContainer: return "container:" + std::to_string(spec.keyframe);
    case render::ViewKind::kGlobal: break;
  }
  return "global";
}

void parseViewName(const std::string& text, render::ViewSpec* spec) {
  std::smatch m;
  static const std::regex pattern(R"((global)|(keyframe|container):(\d{1,9}))");
  if (!std::regex_match(text, m, pattern))
    throw std::invalid_argument("'" + text + "': expected global, keyframe:K or container:K");
  if (m[1].matched) {
    spec->kind = render::ViewKind::kGlobal;
    spec->keyframe = -1;
    return;
  }
  spec->kind = m[2] == "keyframe" ? render::ViewKind::kKeyframe : render::ViewKind::kContainer;
  spec->keyframe = std::stoi(m[3]);
}

render::ViewSpec readViewFile(const fs::path& file, GlobalMapParams* thresholds) {
  const json j = parseFile(file);
  try {
    return specFromJson(j, thresholds);
  } catch (const std::invalid_argument& e) {
    throw InputError(file.string(), e.what());
  }
}

void writeViewFile(const fs::path& file, const render::ViewSpec& spec, const GlobalMapParams& thresholds,
                   const std::string& source) {
  json j = json::object();
  j["vdmap_view"] = kVersion;
  j["source"] = source;
  j["view"] = viewName(spec);
  j["size"] = json::array({spec.width, spec.height});
  if (spec.look_at)
    j["camera"] = {{"eye", vec3Json(spec.look_at->eye)},
                   {"target", vec3Json(spec.look_at->target)},
                   {"up", vec3Json(spec.look_at->up)},
                   {"fov_y_deg", spec.look_at->fov_y_deg}};
  else j["camera"] = nullptr;
  j["up_axis"] = render::kUpAxisNames[static_cast<int>(spec.up)];
  j["up_vector"] = spec.up_vector ? vec3Json(*spec.up_vector) : json(nullptr);
  j["projection"] = render::kProjectionNames[static_cast<int>(spec.projection)];
  j["rotation"] = render::kRotationNames[static_cast<int>(spec.rotation)];
  j["color"] = render::colorModeName(spec.color);
  j["draw"] = render::kDrawModeNames[static_cast<int>(spec.draw())];
  j["slice"] = spec.slice.on ? json::array({spec.slice.lo_m, spec.slice.hi_m}) : json(nullptr);
  j["sigma"] = spec.sigma;
  j["sphere_level"] = spec.sphere_level;
  j["points_below_px"] = spec.points_below_px;
  j["background"] = gui::backgroundName(spec.background);
  json layers = json::object();
  for (std::size_t i = 0; i < std::size(render::kViewLayerNames); ++i)
    layers[render::kViewLayerNames[i]] = spec.layers.*render::kViewLayerFields[i];
  const render::ViewSpec defaults;
  if (!spec.layers.mesh) layers.erase("mesh");  // as files without the mesh read
  if (spec.mesh_style != defaults.mesh_style)
    j["mesh_style"] = render::kMeshStyleNames[static_cast<int>(spec.mesh_style)];
  j["layers"] = layers;
  j["selected_keyframe"] = spec.selected_keyframe;
  ParameterValues params;
  params.global = thresholds;
  json t = json::object();
  for (const Parameter& p : parameters())
    if (p.live) t[std::string(p.key)] = valueJson(p, p.get(params));
  j["thresholds"] = t;
  writeFileAtomically(file, jsonText(j) + "\n");
}

std::string renderCommand(const render::ViewSpec& spec, const CommandSource& source, const std::string& view_file,
                          const std::string& out) {
  std::string cmd = "vdmap render " + shellQuoted(source.path) + source.flags;
  if (!view_file.empty())
    return cmd + " --view-file " + shellQuoted(view_file) +
           (source.thresholds.empty() ? "" : " --settings " + shellQuoted(view_file)) + " --out " + shellQuoted(out);
  cmd += source.thresholds;
  const render::ViewSpec defaults;
  cmd += " --view " + viewName(spec);
  if (spec.width > 0 && spec.height > 0)
    cmd += " --size " + std::to_string(spec.width) + "x" + std::to_string(spec.height);
  if (spec.look_at) {
    const render::LookAt& l = *spec.look_at;
    cmd += " --look-at " + number(l.eye.x) + "," + number(l.eye.y) + "," + number(l.eye.z) + "," + number(l.target.x) +
           "," + number(l.target.y) + "," + number(l.target.z);
    if (l.fov_y_deg != defaults.fov_y_deg) cmd += " --fov " + number(l.fov_y_deg);
  } else if (spec.orbit) {
    cmd += " --orbit " + number(spec.orbit->azimuth_deg) + "," + number(spec.orbit->elevation_deg);
    if (spec.orbit->distance_m) cmd += "," + number(*spec.orbit->distance_m);
  }
  if (!spec.look_at && spec.fov_y_deg != defaults.fov_y_deg) cmd += " --fov " + number(spec.fov_y_deg);
  if (spec.look_at) {
    const glm::vec3& u = spec.look_at->up;
    cmd += " --up " + number(u.x) + "," + number(u.y) + "," + number(u.z);
  } else if (spec.up_vector) {
    const glm::vec3& u = *spec.up_vector;
    cmd += " --up " + number(u.x) + "," + number(u.y) + "," + number(u.z);
  } else if (spec.up != defaults.up) {
    cmd += std::string(" --up ") + render::kUpAxisNames[static_cast<int>(spec.up)];
  }
  if (spec.projection != defaults.projection)
    cmd += std::string(" --projection ") + render::kProjectionNames[static_cast<int>(spec.projection)];
  if (spec.color != defaults.color) cmd += std::string(" --color ") + render::colorModeName(spec.color);
  if (spec.draw() != defaults.draw())
    cmd += std::string(" --draw ") + render::kDrawModeNames[static_cast<int>(spec.draw())];
  if (spec.slice.on) cmd += " --slice " + number(spec.slice.lo_m) + ":" + number(spec.slice.hi_m);
  if (spec.sigma != defaults.sigma) cmd += " --sigma " + number(spec.sigma);
  if (spec.sphere_level != defaults.sphere_level) cmd += " --sphere-level " + std::to_string(spec.sphere_level);
  if (spec.points_below_px != defaults.points_below_px) cmd += " --points-below " + number(spec.points_below_px);
  if (spec.background != defaults.background)
    cmd += " --background " + shellQuoted(gui::backgroundName(spec.background));
  if (spec.layers != defaults.layers) {
    std::string list;
    for (std::size_t i = 0; i < std::size(render::kViewLayerNames); ++i)
      if (spec.layers.*render::kViewLayerFields[i])
        list += (list.empty() ? "" : ",") + std::string(render::kViewLayerNames[i]);
    cmd += " --layers " + (list.empty() ? std::string("none") : list);
  }
  if (spec.mesh_style != defaults.mesh_style)
    cmd += std::string(" --mesh-style ") + render::kMeshStyleNames[static_cast<int>(spec.mesh_style)];
  if (spec.selected_keyframe >= 0) cmd += " --select " + std::to_string(spec.selected_keyframe);
  return cmd + " --out " + shellQuoted(out);
}

bool isViewFile(const fs::path& file) {
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) return false;  // the settings reader says why
  std::ifstream in(file);
  if (!in) return false;
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const json j = json::parse(markNonFinite(text), nullptr, false);
  return !j.is_discarded() && j.is_object() && j.contains("vdmap_view");
}

gui::Settings readSettingsArg(const fs::path& file, const gui::Settings& base) {
  if (!isViewFile(file)) return gui::readSettingsFile(file, base);
  gui::Settings s = base;
  readViewFile(file, &s.thresholds);
  return s;
}

}  // namespace vdmap::app
