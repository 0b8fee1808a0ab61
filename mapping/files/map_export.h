#pragma once
// Everything a mapping run exports (docs/method.md 11), written into one folder: the same code for
// `vdmap map --out DIR` and the workbench's Export button.
#include <filesystem>
#include <functional>

#include <nlohmann/json.hpp>

#include "mapping/files/octomap_export.h"
#include "mapping/global_map/global_map.h"
#include "mapping/io/trajectory_io.h"
#include "mapping/keyframe/keyframe_graph.h"

namespace vdmap {

/// What to export besides the files that are always written.
struct MapExportOptions {
  /// > 0: also write global.bt, an OctoMap of this resolution (m) sampled from the global map.
  double octomap_resolution_m = 0.0;
  /// Files written of the files before global.bt (the PLYs and text files), after each.
  ExportProgress progress;
  /// Progress of the OctoMap export, its slow part (its time grows with the map and with a finer
  /// resolution).
  ExportProgress octomap_progress;
  /// The caller's own figures (e.g. frames and per-frame times of the run), merged into
  /// stats.json; the global-map and export figures are added by exportMap.
  nlohmann::json run_stats = nlohmann::json::object();
  /// Non-empty: also write trajectory.txt, the pose of every mapped frame (Mapper::trajectory()).
  std::vector<StampedPose> trajectory;
  /// Set: called once every file is staged, before any is put in place; what it throws fails
  /// the export, which then leaves nothing. `vdmap map --save` saves its session here, so that a
  /// run whose save fails (a full disk) keeps no new export, and one whose export fails no new
  /// session.
  std::function<void()> before_commit;
};

/// Writes into `dir` (created if missing):
///   local_maps.ply        localEllipsoids(graph, map): the local maps, world frame (docs/method.md 11 ellipsoid PLY)
///   keyframes.txt         keyframe poses T_W_K, TUM format, line i = keyframe i
///   trajectory.txt        only with options.trajectory: every mapped frame's T_W_C, TUM format
///   graph.txt             covisibility edges `a b weight`
///   global_points.ply     global-map ellipsoid means with colour
///   global_ellipsoids.ply global-map ellipsoids (docs/method.md 11)
///   global_gaussians.ply  global-map ellipsoids as 3-D Gaussian splats (docs/method.md 11)
///   global.bt             only with options.octomap_resolution_m > 0 (octomap_export.h)
///   stats.json            options.run_stats + the global-map and export figures
/// All files are first written into a staging folder inside `dir` (.vdmap-export-PID) and then
/// renamed into place, so a failure (unwritable folder, full disk) leaves no file of this export
/// behind and earlier files of the same names untouched; an interrupt removes the staging folder
/// when installTemporaryPathCleanup() is in place, and staging folders of dead processes are
/// removed by the next export into `dir`. Files of this list that an earlier export wrote and
/// this one does not (global.bt) are removed once the new ones are in place, so the folder holds
/// one run. Throws std::runtime_error naming the folder or file.
/// Reads `graph` and `map` only; the caller keeps them unchanged for the duration of the call.
/// Throws std::invalid_argument for a negative or non-finite octomap resolution, or one the map
/// does not fit in (checkOctomapResolution), before writing.
/// Returns the stats that were written to stats.json.
nlohmann::json exportMap(const std::filesystem::path& dir, const KeyframeGraph& graph, const GlobalMap& map,
                         const MapExportOptions& options = {});

/// Throws std::runtime_error when `dir` cannot become an export folder (it exists and is not a
/// folder, or the nearest existing folder on its path is not writable), so a caller can fail
/// before long work. Creates nothing.
void checkExportFolder(const std::filesystem::path& dir);

/// The global-map figures of stats.json: keyframes, edges, groups, sigma_e, merged,
/// sigma_e_prime, t_g_s, t_g_us_per_ellipsoid and the stage times in ms.
nlohmann::json globalMapStats(const KeyframeGraph& graph, const GlobalMap& map);

}  // namespace vdmap
