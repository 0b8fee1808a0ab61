// vdmap eval --map DIR_or_PLY --mesh PLY: reconstruction accuracy against a reference mesh
// (docs/method.md 12). The map is any PLY with vertex positions: vdmap's ellipsoid or point
// exports, OctoMap voxel centres, the NDT-OM baseline's cell means, a TSDF's point cloud.
// vdmap eval --trajectory EST --groundtruth GT: trajectory error as the TUM benchmark's tools
// (mapping/eval/trajectory_error.h).
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

#include "app/cli/command_line.h"
#include "app/cli/eval_report.h"
#include "app/verbs.h"
#include "mapping/core/error.h"
#include "mapping/io/json_text.h"

namespace vdmap::app {
namespace {

struct EvalArgs {
  std::string map;
  std::string mesh;
  std::string trajectory;
  std::string groundtruth;
  bool json = false;
  bool surface = false;
  AccuracyParams accuracy;
  TrajectoryErrorParams trajectory_error;
};

void runTrajectoryEval(const EvalArgs& args) {
  const TrajectoryError e = evaluateTrajectoryFiles(args.trajectory, args.groundtruth, args.trajectory_error);
  if (args.json) {
    nlohmann::json out = toJson(e, args.trajectory_error);
    out["trajectory"] = args.trajectory;
    out["groundtruth"] = args.groundtruth;
    std::cout << jsonText(out) << "\n";
    return;
  }
  std::cout << args.trajectory << " against " << args.groundtruth << ": " << toText(e, args.trajectory_error);
}

// --surface: the map is a triangle mesh, scored by samples over its area.
void runSurfaceEval(const EvalArgs& args, const std::filesystem::path& map) {
  const ColoredTriangleMesh surface = readPlyMesh(map);
  const ColoredTriangleMesh mesh = readPlyMesh(args.mesh);
  const SurfaceAccuracyReport r = evaluateSurfaceAccuracy(surface, mesh, args.accuracy);
  if (args.json) {
    const nlohmann::json out = {{"map", map.string()},
                                {"mesh", args.mesh},
                                {"triangles", r.triangles},
                                {"median_mm", rounded(r.median_mm)},
                                {"p95_mm", rounded(r.p95_mm)},
                                {"mean_mm", rounded(r.mean_mm)},
                                {"rmse_mm", rounded(r.rmse_mm)},
                                {"completion_ratio", rounded(r.completion_ratio)},
                                {"completion_within_m", args.accuracy.completion_within_m},
                                {"samples", args.accuracy.completion_samples}};
    std::cout << jsonText(out) << "\n";
    return;
  }
  std::printf("%s against %s: %zu triangles  median %.2f mm  p95 %.2f mm  mean %.2f mm  RMSE %.2f mm  "
              "completion %.1f%% within %g cm\n",
              map.c_str(), args.mesh.c_str(), r.triangles, r.median_mm, r.p95_mm, r.mean_mm, r.rmse_mm,
              100.0 * r.completion_ratio, 100.0 * args.accuracy.completion_within_m);
}

void runEval(const EvalArgs& args) {
  if (!args.trajectory.empty()) return runTrajectoryEval(args);
  if (args.map.empty())
    throw CLI::RequiredError("nothing to evaluate: give --map and --mesh, or --trajectory and --groundtruth",
                             CLI::ExitCodes::RequiredError);
  namespace fs = std::filesystem;
  fs::path map = args.map;
  // A `vdmap map` output folder is scored by its global map's ellipsoid means.
  if (fs::is_directory(map)) map /= "global_points.ply";
  if (!fs::exists(map)) throw InputError(map.string(), "no such file (expected a PLY or a `vdmap map` folder)");
  if (args.surface) return runSurfaceEval(args, map);
  const std::vector<Eigen::Vector3f> points = readPlyPoints(map);
  const ColoredTriangleMesh mesh = readPlyMesh(args.mesh);
  const AccuracyReport report = evaluateAccuracy(points, mesh, args.accuracy);
  if (args.json) {
    nlohmann::json out = toJson(report);
    out["map"] = map.string();
    out["mesh"] = args.mesh;
    out["triangles"] = mesh.triangles.size();
    out["completion_samples"] = args.accuracy.completion_samples;
    std::cout << jsonText(out) << "\n";
    return;
  }
  std::cout << map.string() << " against " << args.mesh << " (" << mesh.triangles.size() << " triangles)\n"
            << toText(report) << "\n";
}

}  // namespace

void addEvalCommand(CLI::App& app) {
  auto* verb = app.add_subcommand(
      "eval", "Reconstruction accuracy against a reference mesh (docs/method.md 12), or trajectory error against "
              "ground truth (ATE after rigid alignment, RPE; TUM benchmark definitions)");
  auto args = std::make_shared<EvalArgs>();
  auto* map = verb->add_option(
      "--map", args->map, "map to score: a PLY with vertex x y z (ellipsoids, points) or a `vdmap map` output folder");
  // A missing mesh is a file's error (exit 1), read before any work.
  auto* mesh = verb->add_option("--mesh", args->mesh, "reference triangle mesh (PLY, same world frame, metres)");
  verb->add_option("--samples", args->accuracy.completion_samples, "mesh samples for completion")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, AccuracyParams::kMaxCompletionSamples));
  auto* surface = verb->add_flag("--surface", args->surface,
                                 "the map is a triangle mesh PLY (vdmap mesh, a TSDF's mesh): score samples over its "
                                 "area, and completion as the reference's samples' distance to it");
  verb->add_option("--within", args->accuracy.completion_within_m,
                   "m: a reference sample is complete when the map is this close")
      ->check(positiveFiniteCheck())
      ->capture_default_str();
  surface->needs(map);
  map->needs(mesh);
  mesh->needs(map);
  auto* trajectory = verb->add_option("--trajectory", args->trajectory,
                                      "estimated trajectory to score (TUM: timestamp tx ty tz qx qy qz qw)");
  auto* groundtruth = verb->add_option("--groundtruth", args->groundtruth, "ground-truth trajectory (TUM)");
  trajectory->needs(groundtruth);
  groundtruth->needs(trajectory);
  trajectory->excludes(map);
  TrajectoryErrorParams& te = args->trajectory_error;
  verb->add_option("--max-difference", te.max_difference_s,
                   "seconds: poses match when their timestamps differ by less (associate.py)")
      ->check(positiveFiniteCheck())
      ->capture_default_str();
  verb->add_option("--offset", te.offset_s, "seconds added to the trajectory's timestamps before matching")
      ->check(finiteCheck())
      ->capture_default_str();
  verb->add_flag("--align-scale", te.align_scale,
                 "align with a similarity (fit a scale, e.g. monocular) instead of rigidly");
  verb->add_option("--delta", te.rpe_delta_s, "seconds between the poses of the per-second relative pose error")
      ->check(positiveFiniteCheck())
      ->capture_default_str();
  verb->add_flag("--json", args->json, "print JSON instead of text");
  verb->callback([args] { runEval(*args); });
}

}  // namespace vdmap::app
