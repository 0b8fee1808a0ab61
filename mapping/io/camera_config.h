#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "mapping/core/camera.h"

namespace vdmap {

/// The named camera presets of SPEC section 1, in a stable order.
const std::vector<std::string>& cameraPresetNames();

/// The preset's intrinsics and depth scale. Throws std::invalid_argument listing the valid
/// names when `name` is unknown.
PinholeCamera cameraPreset(const std::string& name);

/// Reads a camera file (camera.yaml, camera.json, or the nvblox/NICE-SLAM cam_params.json with
/// its "camera" block). Keys: fx, fy, cx, cy, depth_scale (or "scale"), width/w, height/h;
/// a file may name a `preset` and override some keys of it. Throws InputError naming the file
/// and the missing or malformed key.
PinholeCamera readCameraFile(const std::filesystem::path& file);

/// The camera of a sequence folder, and a sentence saying where it came from.
struct CameraChoice {
  PinholeCamera camera;
  std::string source;
};

/// Chooses the camera of a sequence folder: `preset_override` when not empty; else a
/// camera.yaml / camera.json / cam_params.json in the folder; else a preset the folder names
/// (its name or its depth file names: 7scenes, icl-nuim, replica, freiburg1/2/3); else
/// tum-default.
CameraChoice chooseCamera(const std::filesystem::path& folder, const std::string& preset_override);

}  // namespace vdmap
