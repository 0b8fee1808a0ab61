#include "mapping/files/map_export.h"
#include "mapping/core/message_text.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

#include "mapping/core/atomic_file.h"
#include "mapping/core/temporary_paths.h"
#include "mapping/core/timing.h"
#include "mapping/files/octomap_export.h"
#include "mapping/files/ply_writer.h"
#include "mapping/io/json_text.h"
#include "mapping/io/trajectory_io.h"

namespace vdmap {
namespace {

namespace fs = std::filesystem;

// Every file an export can write; a new export removes those of an older one it does not write
// (a global.bt from a run with --octomap), so the folder never mixes two runs.
const char* const kExportFiles[] = {"local_maps.ply",        "keyframes.txt",        "graph.txt", "global_points.ply",
                                    "global_ellipsoids.ply", "global_gaussians.ply", "global.bt", "stats.json"};
constexpr char kStagingPrefix[] = ".vdmap-export-";

// Removes the staging folders of exports whose process is gone (killed with SIGKILL, or before
// the interrupt cleanup existed). A live process's folder is left alone.
void removeStaleStagingFolders(const fs::path& dir) {
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    if (!isStaleTemporaryName(entry.path().filename().string(), kStagingPrefix)) continue;
    std::error_code ignored;
    fs::remove_all(entry.path(), ignored);
  }
}

// Every value the export writes must read back: vdmap's readers refuse non-finite values, and the
// PLYs' float32 fields turn values beyond 3.4e38 into inf. Maps of valid input never fail this
// (input poses lie within kMaxPoseDistanceM); if one does, the run fails rather than write
// files that its own readers refuse.
void checkWritable(const fs::path& dir, const char* which, const EllipsoidSource& ellipsoids) {
  constexpr double kFloatMax = std::numeric_limits<float>::max();
  std::size_t i = 0;
  ellipsoids([&](const Ellipsoid& e) {
    if ((e.mean.array().abs() <= kFloatMax).all() && (e.cov.array().abs() <= kFloatMax).all() && e.color.allFinite()) {
      ++i;
      return;
    }
    throw std::runtime_error(dir.string() + ": nothing exported: " + which + " ellipsoid " + std::to_string(i) +
                             " (keyframe " + std::to_string(e.keyframe) +
                             ") has a mean or covariance that is not a "
                             "finite float (mean " +
                             shortNumber(e.mean.x()) + " " + shortNumber(e.mean.y()) + " " + shortNumber(e.mean.z()) +
                             ")");
  });
}

void checkWritable(const fs::path& dir, const char* which, const std::vector<StampedPose>& poses) {
  for (std::size_t i = 0; i < poses.size(); ++i)
    if (!std::isfinite(poses[i].t) || !poses[i].T_W_C.matrix().allFinite())
      throw std::runtime_error(dir.string() + ": nothing exported: " + which + " pose " + std::to_string(i) +
                               " is not finite");
}

// A folder inside the export folder that receives every file first; commit() renames them into
// the export folder (same file system, so each rename is atomic), and the destructor removes
// whatever is left, so a failed export leaves nothing of itself behind. The folder and its files
// are registered as temporary paths, so an interrupt (SIGINT, SIGTERM) removes them as well.
class StagingFolder {
 public:
  explicit StagingFolder(const fs::path& dir) : dir_(dir), path_(dir / (kStagingPrefix + std::to_string(::getpid()))) {
    checkExportFolder(dir);
    std::error_code ec;
    if (!fs::exists(dir, ec)) created_ = std::make_unique<TemporaryPath>(dir, true);
    fs::create_directories(dir, ec);
    if (ec) throw std::runtime_error(dir.string() + ": cannot create the output folder (" + ec.message() + ")");
    removeStaleStagingFolders(dir);
    fs::remove_all(path_, ec);
    registered_ = std::make_unique<TemporaryPath>(path_, true);
    if (!fs::create_directory(path_, ec) || ec)
      throw std::runtime_error(dir.string() + ": cannot write into the output folder (" +
                               (ec ? ec.message() : std::string("exists")) + ")");
  }
  ~StagingFolder() {
    std::error_code ec;
    fs::remove_all(path_, ec);
    if (created_ && !committed_) fs::remove(dir_, ec);  // only when empty: the folder this export made
  }
  StagingFolder(const StagingFolder&) = delete;
  StagingFolder& operator=(const StagingFolder&) = delete;

  /// Where to write `name` (one of kExportFiles) now.
  fs::path operator/(const std::string& name) {
    names_.push_back(name);
    files_.push_back(std::make_unique<TemporaryPath>(path_ / name));
    return path_ / name;
  }
  /// Moves every staged file into the export folder and removes the files of kExportFiles
  /// that this export did not write.
  void commit() {
    for (const std::string& name : names_)  // a rename would fail half-way through the set
      if (fs::is_directory(dir_ / name))
        throw std::runtime_error((dir_ / name).string() + ": cannot write (a folder of that name is in the way)");
    for (const std::string& name : names_) {
      std::error_code ec;
      fs::rename(path_ / name, dir_ / name, ec);
      if (ec) throw std::runtime_error((dir_ / name).string() + ": cannot write (" + ec.message() + ")");
    }
    for (const char* name : kExportFiles) {
      if (std::find(names_.begin(), names_.end(), name) != names_.end()) continue;
      std::error_code ec;
      if (fs::is_regular_file(dir_ / name, ec)) fs::remove(dir_ / name, ec);
    }
    committed_ = true;
  }

 private:
  fs::path dir_, path_;
  std::unique_ptr<TemporaryPath> created_;  // the export folder, when this export created it
  std::unique_ptr<TemporaryPath> registered_;
  bool committed_ = false;
  std::vector<std::string> names_;
  std::vector<std::unique_ptr<TemporaryPath>> files_;
};

}  // namespace

void checkExportFolder(const fs::path& dir) {
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw std::runtime_error(dir.string() + ": exists and is not a folder");
  fs::path existing = fs::absolute(dir, ec);
  while (!fs::exists(existing, ec) && existing.has_parent_path() && existing.parent_path() != existing)
    existing = existing.parent_path();
  if (!fs::is_directory(existing, ec))
    throw std::runtime_error(dir.string() + ": cannot create the output folder (" + existing.string() +
                             " is not a folder)");
  if (::access(existing.c_str(), W_OK | X_OK) != 0)
    throw std::runtime_error(dir.string() + ": cannot write into " + existing.string() + " (permission denied)");
}

nlohmann::json globalMapStats(const KeyframeGraph& graph, const GlobalMap& map) {
  return {
      {"keyframes", graph.size()},
      {"edges", graph.edges().size()},
      {"groups", map.groups.size()},
      {"sigma_e", map.sigma_e},
      {"merged", map.merged},
      {"merged_across_groups", map.merged_across_groups},
      {"sigma_e_prime", map.sigma_e_prime},
      {"t_g_s", rounded(map.t_g_s)},
      {"t_g_us_per_ellipsoid", rounded(map.sigma_e > 0 ? map.t_g_s * 1e6 / static_cast<double>(map.sigma_e) : 0.0)},
      {"global_stage_ms",
       {{"groups", rounded(map.groups_ms)},
        {"merge", rounded(map.merge_ms)},
        {"occlusion", rounded(map.occlusion_ms)},
        {"fusion", rounded(map.fusion_ms)}}},
  };
}

nlohmann::json exportMap(const fs::path& dir, const KeyframeGraph& graph, const GlobalMap& map,
                         const MapExportOptions& options) {
  if (!(options.octomap_resolution_m >= 0.0) || !std::isfinite(options.octomap_resolution_m))
    throw std::invalid_argument("octomap resolution must be > 0 m (0: no OctoMap)");
  if (options.octomap_resolution_m > 0.0) checkOctomapResolution(options.octomap_resolution_m, graph, map.ellipsoids);
  std::vector<StampedPose> poses;
  for (const Keyframe& k : graph.keyframes()) poses.push_back({k.timestamp, k.T_W_K});
  const EllipsoidSource local = [&](const EllipsoidVisitor& visit) { forEachLocalEllipsoid(graph, map, visit); };
  checkWritable(dir, "keyframe", poses);
  checkWritable(dir, "trajectory", options.trajectory);
  checkWritable(dir, "local-map", local);
  checkWritable(dir, "global-map", [&](const EllipsoidVisitor& visit) {
    for (const Ellipsoid& e : map.ellipsoids) visit(e);
  });
  StagingFolder stage(dir);
  const std::size_t files = options.trajectory.empty() ? 6 : 7;
  std::size_t written = 0;
  const auto wrote = [&] {
    if (options.progress) options.progress(++written, files);
  };
  writeEllipsoidPly(stage / "local_maps.ply", map.sigma_e, local);
  wrote();
  writeTumTrajectory(stage / "keyframes.txt", poses,
                     "vdmap keyframe poses T_W_K (camera-to-world); line i is keyframe id i");
  wrote();
  if (!options.trajectory.empty()) {
    writeTumTrajectory(stage / "trajectory.txt", options.trajectory,
                       "vdmap frame poses T_W_C (camera-to-world), every mapped frame");
    wrote();
  }
  graph.edges().writeEdgeList(stage / "graph.txt");
  wrote();
  writePointPly(stage / "global_points.ply", map.ellipsoids);
  wrote();
  writeEllipsoidPly(stage / "global_ellipsoids.ply", map.ellipsoids);
  wrote();
  writeGaussianPly(stage / "global_gaussians.ply", map.ellipsoids);
  wrote();

  nlohmann::json stats = options.run_stats.is_object() ? options.run_stats : nlohmann::json::object();
  stats.update(globalMapStats(graph, map));
  if (options.octomap_resolution_m > 0.0) {
    const OctomapExportReport r = writeOctomapBt(stage / "global.bt", graph, map.ellipsoids,
                                                 options.octomap_resolution_m, options.octomap_progress);
    stats["octomap"] = {{"resolution_m", options.octomap_resolution_m},
                        {"points", r.points},
                        {"occupied_leaves", r.occupied_leaves},
                        {"means_occupied", rounded(r.means_occupied)},
                        {"seconds", rounded(r.seconds)}};
  }
  writeFileAtomically(stage / "stats.json", jsonText(stats) + "\n");
  if (options.before_commit) options.before_commit();
  stage.commit();
  return stats;
}

}  // namespace vdmap
