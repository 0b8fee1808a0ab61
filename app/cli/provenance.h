#pragma once
// How an export folder was made, for its stats.json (`vdmap map` and the workbench's Export write
// the same keys): vdmap's version, the sequence and its frames, the camera and where it came from,
// the pose source and every mapping parameter, so that any folder can be made again.
#include <optional>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "mapping/pipeline/parameters.h"
#include "mapping/sequence/sequence.h"
#include "mapping/tracking/map_registration.h"

namespace vdmap::app {

/// vdmap's version as `vdmap --version` prints it without the name: "0.1.0 (git a90ee3c)", or
/// "0.1.0" when the build was not configured from a git checkout (cmake/version.cmake).
std::string versionText();

/// Where a camera came from (Sequence::cameraSource(), CameraChoice::source): "preset" (given
/// with --camera), "file" (a camera file in the folder), "session" (a saved session's) or
/// "guessed" (a preset chosen from the folder's name or file names, or tum-default).
std::string cameraSourceKind(const std::string& source);

/// What made a map, besides its frames.
struct Provenance {
  std::string sequence;       ///< the folder the frames came from ("" when unknown; written absolute)
  std::string camera_source;  ///< Sequence::cameraSource(), or "session FILE"
  PinholeCamera camera;
  PoseSource poses = PoseSource::kGroundTruth;
  /// Tracked poses: how the keyframe poses were refined after the last frame (nullopt: not).
  std::optional<MapRefinementParams> refine;
  ParameterValues params;  ///< every parameter of the table (the thread count does not shape the map)
};

/// stats.json's provenance keys: vdmap_version, sequence, camera (the source sentence),
/// camera_source (cameraSourceKind), camera_intrinsics, poses, refine and parameters (every
/// parameter of the table by its settings key, as settings.json writes it).
nlohmann::json provenanceStats(const Provenance& p);

/// stats.json's frame counts of a sequence as opened: frames_listed (depth frames listed),
/// frames_in_range (of them, inside --frames), frames_dropped_no_rgb and frames_dropped_no_pose
/// (of those, dropped: no rgb frame within 0.02 s, no ground-truth pose within 0.1 s) and
/// frames_mapped (the rest, fed to the mapper).
nlohmann::json frameCounts(const Sequence& seq);

/// One line for stderr when frames of the range were dropped ("" when none were): how many of how
/// many and why; when most of the range was dropped it says so first, in capitals.
std::string droppedFramesWarning(const Sequence& seq);

}  // namespace vdmap::app
