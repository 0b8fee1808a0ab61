#include "app/cli/provenance.h"

#include <cstdio>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "app/cli/parameter_table.h"
#include "vdmap_version.h"

namespace vdmap::app {

std::string versionText() {
  return std::string(kVersion) + (kGitDescribe[0] ? std::string(" (git ") + kGitDescribe + ")" : "");
}

std::string cameraSourceKind(const std::string& source) {
  // The sentences of chooseCamera (camera_config.cpp) and of a session's camera.
  if (source.find("(--camera)") != std::string::npos) return "preset";
  if (source.rfind("file ", 0) == 0) return "file";
  if (source.rfind("session", 0) == 0) return "session";
  return "guessed";
}

namespace {

// `folder` absolute and normal, as a session stores it (sessionInfo).
std::string absoluteFolder(const std::string& folder) {
  if (folder.empty()) return folder;
  std::error_code ec;
  const std::filesystem::path absolute = std::filesystem::absolute(folder, ec);
  return (ec ? std::filesystem::path(folder) : absolute).lexically_normal().string();
}

const char* refineName(const std::optional<MapRefinementParams>& refine) {
  if (!refine) return "none";
  return refine->method == MapRefinementMethod::kPairwise ? "pairwise" : "joint";
}

}  // namespace

nlohmann::json provenanceStats(const Provenance& p) {
  const bool tracking = p.poses == PoseSource::kTrack;
  nlohmann::json parameters = nlohmann::json::object();
  for (const Parameter& row : vdmap::parameters()) parameters[std::string(row.key)] = valueJson(row, row.get(p.params));
  const PinholeCamera& c = p.camera;
  return {
      {"vdmap_version", versionText()},
      {"sequence", absoluteFolder(p.sequence)},
      {"camera", p.camera_source},
      {"camera_source", cameraSourceKind(p.camera_source)},
      {"camera_intrinsics",
       {{"width", c.width},
        {"height", c.height},
        {"fx", c.fx},
        {"fy", c.fy},
        {"cx", c.cx},
        {"cy", c.cy},
        {"depth_scale", c.depth_scale}}},
      {"poses", tracking ? "track" : "gt"},
      // Ground-truth poses are never refined.
      {"refine", tracking ? refineName(p.refine) : "none"},
      {"parameters", parameters},
  };
}

nlohmann::json frameCounts(const Sequence& seq) {
  const DropCounts& d = seq.dropped();
  return {
      {"frames_listed", seq.listedDepthFrames()},
      {"frames_in_range", seq.listedDepthFrames() - d.outside_range},
      {"frames_dropped_no_rgb", d.no_rgb},
      {"frames_dropped_no_pose", d.no_pose},
      {"frames_mapped", seq.size()},
  };
}

std::string droppedFramesWarning(const Sequence& seq) {
  const DropCounts& d = seq.dropped();
  const int dropped = d.no_rgb + d.no_pose;
  if (dropped == 0) return "";
  const int in_range = seq.listedDepthFrames() - d.outside_range;
  std::string why;
  char window[32];
  if (d.no_pose > 0) {
    std::snprintf(window, sizeof window, "%g s", d.max_pose_dt_s);
    why = std::to_string(d.no_pose) + " without a ground-truth pose within " + window +
          " (the recorded poses do not cover them; --poses track maps every frame)";
  }
  if (d.no_rgb > 0) {
    std::snprintf(window, sizeof window, "%g s", d.max_rgb_dt_s);
    why += (why.empty() ? "" : ", ") + std::to_string(d.no_rgb) + " without an rgb frame within " + window +
           " (--rgb-window S pairs colour further away)";
  }
  // More than half of the range gone is rarely what the user meant: say so before the details.
  const std::string most = 2 * dropped > in_range ? "MOST FRAMES DROPPED: " : "";
  return most + std::to_string(dropped) + " of the " + std::to_string(in_range) + " frames of " +
         frameRangeText(seq.frameRange()) + " dropped, " + std::to_string(seq.size()) + " mapped: " + why;
}

}  // namespace vdmap::app
