// vdmap eval --map DIR_or_PLY --mesh PLY: reconstruction accuracy against a reference mesh
// (SPEC section 8). The map is any PLY with vertex positions: vdmap's ellipsoid or point
// exports, OctoMap voxel centres, the NDT-OM baseline's cell means, a TSDF's point cloud.
#include <filesystem>
#include <iostream>
#include <memory>

#include "app/commands.h"
#include "app/eval_report.h"
#include "mapping/core/error.h"

namespace vdmap::app {
namespace {

struct EvalArgs {
  std::string map;
  std::string mesh;
  bool json = false;
  AccuracyParams accuracy;
};

void runEval(const EvalArgs& args) {
  namespace fs = std::filesystem;
  fs::path map = args.map;
  // A `vdmap map` output folder is scored by its global map's ellipsoid means.
  if (fs::is_directory(map)) map /= "global_points.ply";
  if (!fs::exists(map)) throw InputError(map.string(), "no such file (expected a PLY or a `vdmap map` folder)");
  const std::vector<Eigen::Vector3f> points = readPlyPoints(map);
  const ColoredTriangleMesh mesh = readPlyMesh(args.mesh);
  const AccuracyReport report = evaluateAccuracy(points, mesh, args.accuracy);
  if (args.json) {
    nlohmann::json out = toJson(report);
    out["map"] = map.string();
    out["mesh"] = args.mesh;
    out["triangles"] = mesh.triangles.size();
    out["completion_samples"] = args.accuracy.completion_samples;
    std::cout << out.dump(2) << "\n";
    return;
  }
  std::cout << map.string() << " against " << args.mesh << " (" << mesh.triangles.size() << " triangles)\n"
            << toText(report) << "\n";
}

}  // namespace

void addEvalCommand(CLI::App& app) {
  auto* verb = app.add_subcommand("eval", "Reconstruction accuracy against a reference mesh (SPEC section 8)");
  auto args = std::make_shared<EvalArgs>();
  verb->add_option("--map", args->map,
                   "map to score: a PLY with vertex x y z (ellipsoids, points) or a `vdmap map` output folder")
      ->required();
  verb->add_option("--mesh", args->mesh, "reference triangle mesh (PLY, same world frame, metres)")
      ->required()->check(CLI::ExistingFile);
  verb->add_option("--samples", args->accuracy.completion_samples, "mesh samples for completion")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, AccuracyParams::kMaxCompletionSamples));
  verb->add_flag("--json", args->json, "print JSON instead of text");
  verb->callback([args] { runEval(*args); });
}

}  // namespace vdmap::app
