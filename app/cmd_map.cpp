// vdmap map SEQ --out DIR: the whole mapping path. Frames go through the Mapper (features,
// keyframe decision, local-map update; or a fixed keyframe schedule with --keyframe-every), then
// the global map is built from the local maps and exported with exportMap (map_export.h).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>

#include <nlohmann/json.hpp>

#include "app/commands.h"
#include "app/map_sequence.h"
#include "app/parameter_table.h"
#include "app/progress.h"
#include "app/timing.h"
#include "mapping/export/map_export.h"
#include "mapping/eval/trajectory_error.h"
#include "mapping/global_map/global_map.h"
#include "mapping/io/session_file.h"

namespace vdmap::app {
namespace {

struct MapArgs {
  SequenceArgs sequence;
  std::string out;
  std::string save;
  bool json = false;
  MappingParams params;  // every parameter of the table (app/parameter_table.h)
  double octomap_resolution_m = 0.0;
};

void runMap(MapArgs args) {
  namespace fs = std::filesystem;
  validate(args.params);  // each value was checked when parsed; this checks them together (depth range)
  if (!(args.octomap_resolution_m >= 0.0)) throw std::invalid_argument("--octomap must be > 0 m");
  const fs::path out_dir = args.out;
  // Fail before any work when DIR cannot be written; it is created only when there is a map to
  // write, so a failed run leaves nothing behind.
  checkExportFolder(out_dir);
  if (!args.save.empty()) checkOutputFile(args.save, "--save");

  const TumSequence seq = openSequence(args.sequence);
  args.params.mapper.poses = poseSource(args.sequence, seq);
  const bool tracking = args.params.mapper.poses == PoseSource::kTrack;
  Mapper mapper(seq.camera(), args.params.mapper);
  std::vector<double> update_ms, pipeline_ms, features_ms, decision_ms, tracking_ms;
  mapSequence(seq, mapper, [&](const FrameReport& r) {
    update_ms.push_back(r.ms.update_ms);
    pipeline_ms.push_back(r.ms.total_ms);
    features_ms.push_back(r.ms.features_ms);
    decision_ms.push_back(r.ms.decision_ms);
    tracking_ms.push_back(r.ms.tracking_ms);
  });
  const KeyframeGraph& graph = mapper.graph();
  const GlobalMap global = buildGlobalMap(graph, args.params.global);

  if (!args.json) {
    std::printf("keyframe  frame  frames  ellipsoids    kept  memory\n");
    for (const Keyframe& k : graph.keyframes()) {
      const std::vector<bool>& kept = global.kept[static_cast<std::size_t>(k.id)];
      std::printf("%8d  %5d  %6d  %10zu  %6td  %4.1f MB\n", k.id, k.frame_index, k.frames_integrated,
                  k.container.size(), std::count(kept.begin(), kept.end(), true), k.container.memoryBytes() / 1e6);
    }
  }
  MapExportOptions options;
  options.octomap_resolution_m = args.octomap_resolution_m;
  options.run_stats = {
      {"frames", mapper.framesMapped()},
      {"revisits", mapper.revisits()},
      {"update_ms", median(update_ms)},
      {"pipeline_ms", median(pipeline_ms)},
      {"features_ms", median(features_ms)},
      {"decision_ms", median(decision_ms)},
      {"camera", seq.cameraSource()},
      {"poses", tracking ? "track" : "gt"},
  };
  options.trajectory = mapper.trajectory();
  if (tracking) {
    options.run_stats["tracking_ms"] = median(tracking_ms);
    options.run_stats["frames_lost"] = mapper.framesLost();
    double pose_graph_ms = 0;
    for (const LoopClosure& loop : mapper.poseGraph().loops()) pose_graph_ms += loop.pose_graph_ms;
    options.run_stats["loop_closures"] = mapper.poseGraph().loops().size();
    options.run_stats["pose_graph_ms"] = pose_graph_ms;  // all optimisations of the run, wall clock
    const std::vector<StampedPose> groundtruth = groundTruthTrajectory(seq);
    if (groundtruth.size() >= 3 && options.trajectory.size() >= 3)
      options.run_stats["ate_rmse_m"] = evaluateTrajectory(options.trajectory, groundtruth).ate_m.rmse;
  }
  std::unique_ptr<ProgressBar> octomap_bar;
  options.octomap_progress = [&octomap_bar](std::size_t done, std::size_t total) {
    if (!octomap_bar) octomap_bar = std::make_unique<ProgressBar>("OctoMap export", total);
    octomap_bar->update(done);
  };
  const nlohmann::json stats = exportMap(out_dir, graph, global, options);
  octomap_bar.reset();  // its last line before the summary, not after it
  // After the export, so a failed export leaves no session file behind.
  if (!args.save.empty()) saveSession(args.save, graph, sessionInfo(mapper, args.params.global));
  if (args.json) {
    std::cout << stats.dump(2) << "\n";
    return;
  }
  std::printf("%d frames, %zu keyframes, %zu edges, %d revisits; %zu kept ellipsoids -> %zu in the global map "
              "(t_g %.3f s)\nmedian per frame: pipeline %.2f ms (features %.2f, tracking %.2f, decision %.2f, "
              "update %.2f) -> %s\n",
              mapper.framesMapped(), graph.size(), graph.edges().size(), mapper.revisits(), global.sigma_e,
              global.sigma_e_prime, global.t_g_s, median(pipeline_ms), median(features_ms), median(tracking_ms),
              median(decision_ms), median(update_ms), out_dir.c_str());
  if (tracking) {
    std::printf("tracked poses: %d frames lost (skipped), %zu loop closures", mapper.framesLost(),
                mapper.poseGraph().loops().size());
    if (stats.contains("ate_rmse_m")) std::printf(", ATE %.2f cm against groundtruth.txt", 100 * stats["ate_rmse_m"].get<double>());
    std::printf("\n");
  }
}

}  // namespace

void addMapCommand(CLI::App& app) {
  auto* verb = app.add_subcommand("map", "Map a sequence: keyframes with local maps, covisibility graph, global map");
  auto args = std::make_shared<MapArgs>();
  addSequenceArgs(*verb, args->sequence);
  addPoseSourceArg(*verb, args->sequence);
  verb->add_option("--out", args->out,
                   "output folder (created if missing): local_maps.ply, keyframes.txt, trajectory.txt, graph.txt, "
                   "global_points.ply, global_ellipsoids.ply, global_gaussians.ply, [global.bt], stats.json")
      ->required();
  verb->add_option("--save", args->save, "also save the whole session (a .vdmap file, docs/vdmap-format.md)");
  verb->add_option("--octomap", args->octomap_resolution_m,
                   "also write global.bt, an OctoMap of this resolution (m) sampled from the global map");
  verb->add_flag("--json", args->json, "print stats.json to stdout instead of the table");
  addParameterOptions(*verb, args->params);
  verb->add_option("--threads", args->params.global.threads, "global-map threads (0: all); the map does not depend on it")
      ->capture_default_str();
  verb->callback([args] { runMap(*args); });
}

}  // namespace vdmap::app
