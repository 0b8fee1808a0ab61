#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include <optional>

#include "mapping/core/camera.h"
#include "mapping/core/colour_registration.h"

namespace vdmap {

/// The named camera presets of docs/method.md 1, in a stable order.
const std::vector<std::string>& cameraPresetNames();

/// The preset's intrinsics and depth scale. Throws std::invalid_argument listing the valid
/// names when `name` is unknown.
PinholeCamera cameraPreset(const std::string& name);

/// The preset's colour camera when its colour images are not registered to the depth (7scenes),
/// else nothing. Throws like cameraPreset.
std::optional<ColourCamera> cameraPresetColour(const std::string& name);

/// Reads a camera file (camera.yaml, camera.json, or the nvblox/NICE-SLAM cam_params.json with
/// its "camera" block). Keys: fx, fy, cx, cy, depth_scale (or "scale"), width/w, height/h;
/// a file may name a `preset` and override some keys of it. Any other key is an error (a
/// misspelt key would otherwise leave the preset's value silently). Unregistered colour: a map
/// `colour: {fx, fy, cx, cy, T_colour_depth: [12 numbers, the 3x4 [R|t] row by row, metres]}`
/// (T_colour_depth defaults to the identity), or `colour: registered` to drop a preset's colour
/// camera. Throws InputError naming the file and the missing or malformed key.
PinholeCamera readCameraFile(const std::filesystem::path& file, std::optional<ColourCamera>* colour = nullptr);

/// The camera of a sequence folder, and a sentence saying where it came from.
struct CameraChoice {
  PinholeCamera camera;
  std::string source;
  std::optional<ColourCamera> colour = {};  ///< set when the colour images need registering
  bool guessed = false;                     ///< a preset guessed from the folder's name or file names, or the default
};

/// Chooses the camera of a sequence folder: `preset_override` when not empty; else a
/// camera.yaml / camera.json / cam_params.json in the folder; else a preset the folder names
/// (its name or its depth file names: 7scenes, icl-nuim, replica, freiburg1/2/3); else
/// tum-default.
CameraChoice chooseCamera(const std::filesystem::path& folder, const std::string& preset_override);

}  // namespace vdmap
