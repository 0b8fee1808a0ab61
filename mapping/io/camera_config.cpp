#include "mapping/io/camera_config.h"
#include "mapping/io/text_list.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "mapping/core/error.h"
#include "mapping/core/types.h"

namespace vdmap {
namespace {

struct Preset {
  const char* name;
  PinholeCamera camera;
  std::optional<ColourCamera> colour = {};
};

// 7-Scenes' colour camera: the 525 px focal length its authors give, and the Kinect v1
// depth-to-colour pose of the LIRIS calibration (projet.liris.cnrs.fr/voir/activities-dataset/
// kinect-calibration.html; what Brachmann et al. use to register 7-Scenes). Re-orthonormalised.
ColourCamera sevenScenesColour() {
  Eigen::Matrix3d R;
  R << 9.9996518012567637e-01, 2.6765126468950343e-03, -7.9041012313000904e-03,  //
      -2.7409311281316700e-03, 9.9996302803027592e-01, -8.1504520778013286e-03,  //
      7.8819942130445332e-03, 8.1718328771890631e-03, 9.9993554558014031e-01;
  ColourCamera c{525.0, 525.0, 320.0, 240.0, Transform::Identity()};
  c.T_colour_depth.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();
  c.T_colour_depth.translation() =
      Eigen::Vector3d(-2.5558943178152542e-02, 1.0109636268061706e-04, 2.0318321729487039e-03);
  return c;
}

// The presets of docs/method.md 1. Sizes are those of the data sets the presets are named after.
const std::vector<Preset>& presets() {
  static const std::vector<Preset> kPresets = {
      {"tum-fr1", {640, 480, 517.306, 516.469, 318.643, 255.314, 5000.0}},
      {"tum-fr2", {640, 480, 520.909, 521.007, 325.141, 249.702, 5000.0}},
      {"tum-fr3", {640, 480, 535.4, 539.2, 320.1, 247.6, 5000.0}},
      {"tum-default", {640, 480, 525.0, 525.0, 319.5, 239.5, 5000.0}},
      {"icl-nuim", {640, 480, 481.2, 480.0, 319.5, 239.5, 5000.0}},
      {"7scenes", {640, 480, 585.0, 585.0, 320.0, 240.0, 1000.0}, sevenScenesColour()},
      {"replica", {1200, 680, 600.0, 600.0, 599.5, 339.5, 6553.5}},
  };
  return kPresets;
}

// Reads a number under one of `keys` (first present wins); returns false when none is present.
bool readNumber(const YAML::Node& node, std::initializer_list<const char*> keys, const std::string& file, double* out) {
  for (const char* key : keys) {
    const YAML::Node value = node[key];
    if (!value) continue;
    try {
      *out = value.as<double>();
    } catch (const YAML::Exception&) {
      throw InputError(file, value.Mark().line + 1, std::string("key '") + key + "' must be a number");
    }
    return true;
  }
  return false;
}

// Fails on the first key of `node` (a map) that is not one of `valid`, naming it and the valid ones.
void checkKeys(const YAML::Node& node, std::initializer_list<const char*> valid, const std::string& file,
               const std::string& block) {
  for (const auto& entry : node) {
    const std::string key = entry.first.Scalar();
    if (std::any_of(valid.begin(), valid.end(), [&](const char* v) { return key == v; })) continue;
    std::string list;
    for (const char* v : valid) list += (list.empty() ? "" : ", ") + std::string(v);
    throw InputError(file, entry.first.Mark().line + 1,
                     "unknown key '" + key + "'" + block + " (valid keys: " + list + ")");
  }
}

}  // namespace

const std::vector<std::string>& cameraPresetNames() {
  static const std::vector<std::string> kNames = [] {
    std::vector<std::string> names;
    for (const Preset& p : presets()) names.push_back(p.name);
    return names;
  }();
  return kNames;
}

namespace {
const Preset& preset(const std::string& name) {
  for (const Preset& p : presets())
    if (name == p.name) return p;
  std::string list;
  for (const std::string& n : cameraPresetNames()) list += (list.empty() ? "" : ", ") + n;
  throw std::invalid_argument("unknown camera preset '" + name + "' (expected one of: " + list + ")");
}

// The `colour` entry of a camera file (see readCameraFile).
std::optional<ColourCamera> readColour(const YAML::Node& node, const std::string& file) {
  const int line = node.Mark().line + 1;
  if (node.IsScalar() && node.as<std::string>() == "registered") return std::nullopt;
  if (!node.IsMap())
    throw InputError(file, line, "key 'colour' must be a map (fx, fy, cx, cy, T_colour_depth) or 'registered'");
  checkKeys(node, {"fx", "fy", "cx", "cy", "T_colour_depth"}, file, " in 'colour'");
  ColourCamera c;
  for (auto [key, value] : {std::pair{"fx", &c.fx}, {"fy", &c.fy}, {"cx", &c.cx}, {"cy", &c.cy}})
    if (!readNumber(node, {key}, file, value))
      throw InputError(file, line, std::string("colour: missing key '") + key + "'");
  if (!(c.fx > 0 && c.fy > 0 && std::isfinite(c.fx) && std::isfinite(c.fy) && std::isfinite(c.cx) &&
        std::isfinite(c.cy)))
    throw InputError(file, line, "colour: fx and fy must be > 0 and fx, fy, cx, cy finite");
  if (const YAML::Node T = node["T_colour_depth"]) {
    Eigen::Matrix<double, 3, 4> m;
    try {
      if (!T.IsSequence() || T.size() != 12) throw YAML::Exception(T.Mark(), "");
      for (int i = 0; i < 12; ++i) m(i / 4, i % 4) = T[i].as<double>();
    } catch (const YAML::Exception&) {
      throw InputError(file, T.Mark().line + 1,
                       "colour: T_colour_depth must be 12 numbers (the 3x4 [R|t], row by row)");
    }
    c.T_colour_depth.matrix().topRows<3>() = m;
    if (!isValidTransform(c.T_colour_depth, 1e-4))
      throw InputError(file, T.Mark().line + 1,
                       "colour: T_colour_depth is not a finite rigid transform (R must be a rotation)");
    c.T_colour_depth.linear() = Eigen::Quaterniond(c.T_colour_depth.linear()).normalized().toRotationMatrix();
  }
  return c;
}
}  // namespace

PinholeCamera cameraPreset(const std::string& name) { return preset(name).camera; }

std::optional<ColourCamera> cameraPresetColour(const std::string& name) { return preset(name).colour; }

PinholeCamera readCameraFile(const std::filesystem::path& file, std::optional<ColourCamera>* colour) {
  const std::string name = file.string();
  YAML::Node root;
  checkNotAFolder(file);
  try {
    root = YAML::LoadFile(name);
  } catch (const YAML::BadFile&) {
    throw InputError(name, "cannot open camera file");
  } catch (const YAML::ParserException& e) {
    throw InputError(name, e.mark.line + 1, "not valid YAML/JSON: " + e.msg);
  }
  if (!root.IsMap()) throw InputError(name, "expected a map of camera keys (fx, fy, cx, cy, ...)");
  // cam_params.json keeps the camera in a block beside other tools' settings: only the block is ours.
  const bool in_block = root["camera"] && root["camera"].IsMap();
  const YAML::Node node = in_block ? root["camera"] : root;
  checkKeys(node, {"preset", "fx", "fy", "cx", "cy", "depth_scale", "scale", "width", "w", "height", "h", "colour"},
            name, in_block ? " in 'camera'" : "");

  PinholeCamera camera;
  std::optional<ColourCamera> unregistered;
  const bool has_preset = static_cast<bool>(node["preset"]);
  if (has_preset) {
    try {
      const Preset& p = preset(node["preset"].as<std::string>());
      camera = p.camera;
      unregistered = p.colour;
    } catch (const std::exception& e) {
      throw InputError(name, node["preset"].Mark().line + 1, e.what());
    }
  }
  if (node["colour"]) unregistered = readColour(node["colour"], name);
  if (colour) *colour = unregistered;
  double value = 0.0;
  auto field = [&](std::initializer_list<const char*> keys, auto setter) {
    if (readNumber(node, keys, name, &value)) {
      setter(value);
    } else if (!has_preset) {
      throw InputError(name, std::string("missing key '") + *keys.begin() +
                                 "' (a camera file needs fx, fy, cx, cy, depth_scale, width, "
                                 "height, or a 'preset' to start from)");
    }
  };
  field({"fx"}, [&](double v) { camera.fx = v; });
  field({"fy"}, [&](double v) { camera.fy = v; });
  field({"cx"}, [&](double v) { camera.cx = v; });
  field({"cy"}, [&](double v) { camera.cy = v; });
  field({"depth_scale", "scale"}, [&](double v) { camera.depth_scale = v; });
  auto pixels = [&name](const char* key, double v) {
    if (!(v >= 1 && v <= PinholeCamera::kMaxImageSide && v == std::floor(v)))
      throw InputError(name, std::string("key '") + key + "' must be a whole number of pixels within 1.." +
                                 std::to_string(PinholeCamera::kMaxImageSide));
    return static_cast<int>(v);
  };
  field({"width", "w"}, [&](double v) { camera.width = pixels("width", v); });
  field({"height", "h"}, [&](double v) { camera.height = pixels("height", v); });
  try {
    camera.validate();
  } catch (const std::invalid_argument& e) {
    throw InputError(name, e.what());
  }
  return camera;
}

CameraChoice chooseCamera(const std::filesystem::path& folder, const std::string& preset_override) {
  if (!preset_override.empty())
    return {cameraPreset(preset_override), "preset " + preset_override + " (--camera)",
            cameraPresetColour(preset_override)};
  for (const char* file : {"camera.yaml", "camera.yml", "camera.json", "cam_params.json"}) {
    const auto path = folder / file;
    if (std::filesystem::exists(path)) {
      CameraChoice choice{{}, std::string("file ") + file, {}};
      choice.camera = readCameraFile(path, &choice.colour);
      return choice;
    }
  }
  const std::string folder_name = std::filesystem::weakly_canonical(folder).filename().string();
  const std::string name = asciiLower(folder_name);
  struct Hint {
    const char* needle;
    const char* preset;
  };
  for (const Hint& hint :
       {Hint{"7scenes", "7scenes"}, Hint{"7-scenes", "7scenes"}, Hint{"icl", "icl-nuim"}, Hint{"replica", "replica"},
        Hint{"freiburg1", "tum-fr1"}, Hint{"freiburg2", "tum-fr2"}, Hint{"freiburg3", "tum-fr3"},
        Hint{"fr1_", "tum-fr1"}, Hint{"fr2_", "tum-fr2"}, Hint{"fr3_", "tum-fr3"}}) {
    if (name.find(hint.needle) != std::string::npos)
      return {cameraPreset(hint.preset), std::string("preset ") + hint.preset + " (folder name '" + folder_name + "')",
              cameraPresetColour(hint.preset), true};
  }
  // 7-Scenes names its depth maps frame-XXXXXX.depth.png.
  std::ifstream depth_list(folder / "depth.txt");
  for (std::string line; std::getline(depth_list, line);) {
    if (line.empty() || line[0] == '#') continue;
    if (line.find(".depth.png") != std::string::npos)
      return {cameraPreset("7scenes"), "preset 7scenes (7-Scenes depth file names)", cameraPresetColour("7scenes"),
              true};
    break;
  }
  return {cameraPreset("tum-default"), "preset tum-default (no camera file or hint in the folder)", {}, true};
}

}  // namespace vdmap
