// vdmap map SEQ --out DIR: the whole mapping path. Frames go through the Mapper (features,
// keyframe decision, local-map update; or a fixed keyframe schedule with --keyframe-every), then
// the global map is built from the local maps and exported with exportMap (map_export.h).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>

#include <nlohmann/json.hpp>

#include "app/cli/command_line.h"
#include "app/cli/mesh_options.h"
#include "app/cli/parameter_table.h"
#include "app/cli/provenance.h"
#include "app/cli/release_memory.h"
#include "app/cli/sequence_args.h"
#include "app/verbs.h"
#include "app/view/map_sequence.h"
#include "app/view/progress.h"
#include "mapping/core/error.h"
#include "mapping/core/parallel.h"
#include "mapping/core/timing.h"
#include "mapping/files/map_export.h"
#include "mapping/files/occupancy_grid.h"
#include "mapping/files/ply_writer.h"
#include "mapping/files/session_file.h"
#include "mapping/global_map/global_map.h"
#include "mapping/io/json_text.h"
#include "mapping/io/trajectory_io.h"

namespace vdmap::app {
namespace {

struct MapArgs {
  SequenceArgs sequence;
  std::string out;
  std::string save;
  std::string load;
  bool json = false;
  ParameterValues params;             // every parameter of the table (mapping/pipeline/parameters.h)
  double octomap_resolution_m = 0.0;  // 0: no OctoMap (a given value is checked by octomapResolutionCheck)
  // point queries (docs/method.md 13): --grid RES --grid-band LO:HI [--grid-up AXIS], a ROS map_server grid
  double grid_resolution_m = 0.0;  // 0: no grid
  std::string grid_band;
  std::string grid_up = "+z";
  bool mesh = false;  // --mesh: also global_mesh.ply (docs/method.md 14)
  MeshOptions mesh_options;
};

// OctoMap carves free space along each ray from the camera to a surface it measured. vdmap maps
// RGB-D data, depth 0.1-8 m (--min-depth, --max-depth): with voxels coarser than a metre the
// camera and the surfaces it sees share voxels, nothing is carved and a room is a few blocks.
// Published OctoMaps of RGB-D data use 0.01-0.2 m. The finest resolution is bounded by the
// map's extent (checkOctomapResolution), known only once it is mapped.
constexpr double kMaxOctomapResolutionM = 1.0;

CLI::Validator octomapResolutionCheck() {
  return parsedBy(
      [](const std::string& text) {
        char* end = nullptr;
        const double v = std::strtod(text.c_str(), &end);
        if (text.empty() || *end != '\0')
          throw std::invalid_argument("expected a resolution in metres, got '" + text + "'");
        if (!(v > 0.0 && v <= kMaxOctomapResolutionM))
          throw std::invalid_argument("the resolution must be > 0 and at most 1 m (OctoMap needs voxels finer than "
                                      "the camera's depth range to carve free space), got " +
                                      text);
      },
      "RES in (0, 1]");
}

// Fails before any work on options that cannot work together or outputs that cannot be written.
void checkMapArgs(const MapArgs& args) {
  validate(args.params);  // each value was checked when parsed; this checks them together (depth range)
  // DIR is created only when there is a map to write, so a failed run leaves nothing behind.
  checkExportFolder(args.out);
  if (!args.save.empty()) checkOutputFile(args.save, "--save");
  if (args.grid_resolution_m > 0) {
    // Poses lie within kMaxPoseDistanceM and depth within --max-depth: a band beyond both holds
    // nothing of any map. Within, the band is clipped to the map's extent once it is mapped.
    const auto [lo, hi] = parseGridBand(args.grid_band);
    const double depth = args.params.mapper.local_map.depth_range.max_m, reach = kMaxPoseDistanceM + depth;
    char text[256];
    std::snprintf(text, sizeof text,
                  " lies beyond any map: poses lie within %g m of the origin and depth within --max-depth (%g m)",
                  kMaxPoseDistanceM, depth);
    if (lo > reach || hi < -reach) throw std::invalid_argument("--grid-band " + args.grid_band + text);
  }
  checkNotAnInput(args.save, "--save", {{"SEQ", args.sequence.folder}, {"--load", args.load}});
  if (!args.load.empty() && !isSessionPath(args.load))
    throw InputError(args.load, std::filesystem::exists(args.load) ? "not a vdmap session file (--load)"
                                                                   : "no such session file (--load)");
}

// The flags of the re-run parameters, "--cell-size, --min-depth, ...".
std::string rerunFlags() {
  std::string flags;
  for (const Parameter& p : parameters())
    if (!p.live) flags += (flags.empty() ? "" : ", ") + std::string(p.flag);
  return flags;
}

// --load: continue a saved session where it stopped. The mapping parameters are the session's
// (they shaped its local maps; an option that would change them is refused), the frames
// default to those after its last one, and the global-map options apply as given.
Session loadSessionToContinue(MapArgs* args) {
  Session loaded = loadSession(args->load);
  const SessionInfo& info = loaded.info;
  if (info.state.current_keyframe < 0 && loaded.graph.size() > 0)
    throw InputError(args->load, "session format " + std::to_string(info.format_version) +
                                     " does not store the mapper's state, so mapping cannot continue from it (it "
                                     "can still be rendered or opened)");
  if (!sameMapperParams(args->params.mapper, MapperParams{}) && !sameMapperParams(args->params.mapper, info.mapper))
    throw std::invalid_argument("--load: the mapping parameters are the session's; drop the options that change "
                                "them (" +
                                rerunFlags() + ")");
  args->params.mapper = info.mapper;
  // The pose source is the session's too (its keyframes were placed that way).
  const std::string session_poses = info.mapper.poses == PoseSource::kTrack ? "track" : "gt";
  if (!args->sequence.poses.empty() && args->sequence.poses != session_poses)
    throw std::invalid_argument("--poses " + args->sequence.poses + ": " + args->load + " was mapped with --poses " +
                                session_poses + "; drop --poses to continue it");
  args->sequence.poses = session_poses;
  if (args->sequence.frames.empty()) args->sequence.frames = std::to_string(info.state.last_frame_index + 1) + ":";
  return loaded;
}

// The sequence must go on where the loaded session stopped, with its camera.
void checkContinues(const Sequence& seq, const Session& loaded, const std::string& load) {
  const MapperState& state = loaded.info.state;
  if (seq.frameRange().first <= state.last_frame_index)
    throw std::invalid_argument("--frames " + frameRangeText(seq.frameRange()) + ": " + load +
                                " has mapped frames up to " + std::to_string(state.last_frame_index) +
                                "; continue from " + std::to_string(state.last_frame_index + 1));
  if (!(seq.camera() == loaded.info.camera))
    throw InputError(seq.folder().string(), "its camera (" + seq.cameraSource() + ") is not the one of " + load +
                                                " (give --camera to match it)");
}

// Each frame's stage times (FrameReport::ms), ms.
struct FrameTimes {
  std::vector<double> update_ms, pipeline_ms, features_ms, decision_ms, tracking_ms;
  void add(const FrameReport& r) {
    update_ms.push_back(r.ms.update_ms);
    pipeline_ms.push_back(r.ms.total_ms);
    features_ms.push_back(r.ms.features_ms);
    decision_ms.push_back(r.ms.decision_ms);
    tracking_ms.push_back(r.ms.tracking_ms);
  }
};

void printKeyframeTable(const KeyframeGraph& graph, const GlobalMap& global) {
  // memory: the local map (its cells and slot grid) and its frames' free space; not the images.
  std::printf("keyframe  frame  frames  ellipsoids    kept  memory\n");
  for (const Keyframe& k : graph.keyframes()) {
    const std::vector<bool>& kept = global.kept[static_cast<std::size_t>(k.id)];
    const KeyframeMemory m = k.memory();
    std::printf("%8d  %5d  %6d  %10zu  %6td  %4.1f MB\n", k.id, k.frame_index, k.frames_integrated, k.container.size(),
                std::count(kept.begin(), kept.end(), true), (m.ellipsoids + m.cell_slots + m.free_space) / 1e6);
  }
}

// The run's figures for stats.json (exportMap adds the map's).
nlohmann::json runStats(const Mapper& mapper, const Sequence& seq, int frames_loaded, const FrameTimes& t,
                        const MapRefinementResult& refined, const std::vector<StampedPose>& trajectory) {
  const bool tracking = mapper.params().poses == PoseSource::kTrack;
  nlohmann::json stats = {
      {"frames", mapper.framesMapped()},
      {"frame_range", frameRangeText(seq.frameRange())},
      {"frames_loaded", frames_loaded},
      {"revisits", mapper.revisits()},
      {"update_ms", rounded(median(t.update_ms))},
      {"pipeline_ms", rounded(median(t.pipeline_ms))},
      {"features_ms", rounded(median(t.features_ms))},
      {"decision_ms", rounded(median(t.decision_ms))},
  };
  if (!tracking) return stats;
  stats["tracking_ms"] = rounded(median(t.tracking_ms));
  addTrackingStats(mapper, trajectory, seq, &stats);
  stats["map_refinement"] = {{"pairs", refined.pairs},    {"edges", refined.edges},
                             {"rounds", refined.rounds},  {"moved_m", rounded(refined.moved_m)},
                             {"ms", rounded(refined.ms)}, {"refused", refined.refused}};
  return stats;
}

// exportMap with progress bars for the files and the OctoMap export; returns stats.json.
nlohmann::json exportWithProgress(const std::filesystem::path& out_dir, const KeyframeGraph& graph,
                                  const GlobalMap& global, MapExportOptions options) {
  std::unique_ptr<ProgressBar> files_bar, octomap_bar;
  options.progress = [&files_bar](std::size_t done, std::size_t total) {
    if (!files_bar) files_bar = std::make_unique<ProgressBar>("export", total);
    files_bar->update(done);
    if (done == total) files_bar.reset();  // its line ends before the OctoMap's starts
  };
  options.octomap_progress = [&octomap_bar](std::size_t done, std::size_t total) {
    if (!octomap_bar) octomap_bar = std::make_unique<ProgressBar>("OctoMap export", total);
    octomap_bar->update(done);
  };
  if (options.before_commit)  // the session save's bar follows the OctoMap's
    options.before_commit = [&octomap_bar, save = options.before_commit] {
      octomap_bar.reset();
      save();
    };
  const nlohmann::json stats = exportMap(out_dir, graph, global, options);
  octomap_bar.reset();  // its last line before the summary, not after it
  return stats;
}

void printTrackingSummary(const Mapper& mapper, const MapRefinementResult& refined, const nlohmann::json& stats) {
  std::printf("tracked poses: %s lost (skipped), %d placed on a weak estimate, %d relocalised, %s",
              counted(mapper.framesLost(), "frame").c_str(), mapper.framesWeak(), mapper.framesRelocalised(),
              counted(mapper.poseGraph().loops().size(), "loop closure").c_str());
  if (refined.refused)
    std::printf(", keyframe poses kept: the joint refinement of %d local-map pairs ran too far (%.1f s)", refined.pairs,
                1e-3 * refined.ms);
  else
    std::printf(", keyframe poses refined from %d of %d covisible local-map pairs (%d rounds, %.1f mm at most, %.1f s)",
                refined.edges, refined.pairs, refined.rounds, 1e3 * refined.moved_m, 1e-3 * refined.ms);
  if (stats.contains("ate_rmse_m"))
    std::printf(", ATE %.2f cm against groundtruth.txt", 100 * stats["ate_rmse_m"].get<double>());
  std::printf("\n");
}

void printSummary(const Mapper& mapper, const GlobalMap& global, const FrameTimes& t,
                  const std::filesystem::path& out_dir) {
  const KeyframeGraph& graph = mapper.graph();
  const std::string counts = counted(mapper.framesMapped(), "frame") + ", " + counted(graph.size(), "keyframe") + ", " +
                             counted(graph.edges().size(), "edge") + ", " + counted(mapper.revisits(), "revisit");
  std::printf("%s; %zu kept ellipsoids -> %zu in the global map (t_g %.3f s)\nmedian per frame: mapping thread "
              "%.2f ms (ORB %.2f on the prefetch thread, tracking %.2f, decision %.2f, update %.2f) -> %s\n",
              counts.c_str(), global.sigma_e, global.sigma_e_prime, global.t_g_s, median(t.pipeline_ms),
              median(t.features_ms), median(t.tracking_ms), median(t.decision_ms), median(t.update_ms),
              out_dir.c_str());
}

void runMap(MapArgs args) {
  checkMapArgs(args);
  std::optional<Session> loaded;
  if (!args.load.empty()) loaded.emplace(loadSessionToContinue(&args));
  std::optional<SequenceContinuation> continues;
  if (loaded)
    continues = SequenceContinuation{args.load, loaded->info.sequence, loaded->info.state.last_frame_index,
                                     loaded->info.state.last_timestamp};
  const Sequence seq = openSequence(args.sequence, false, continues);
  noteCameraGuess(seq, "map");
  if (const std::string dropped = droppedFramesWarning(seq); !dropped.empty())
    std::cerr << "vdmap map: warning: " << dropped << "\n";
  if (loaded) checkContinues(seq, *loaded, args.load);
  else args.params.mapper.poses = poseSource(args.sequence, seq);
  checkRefinementApplies(args.sequence, args.params.mapper.poses);
  Mapper mapper = loaded ? Mapper(loaded->info.camera, args.params.mapper, std::move(loaded->graph), loaded->info.state)
                         : Mapper(seq.camera(), args.params.mapper);
  const int frames_loaded = mapper.framesMapped();
  FrameTimes times;
  const MapRefinementResult refined = mapSequence(
      seq, mapper, [&](const FrameReport& r) { times.add(r); }, refinement(args.sequence));
  const KeyframeGraph& graph = mapper.graph();
  releaseFreedMemory();  // the frames' freed buffers, before the build's peak
  const GlobalMap global = withStageBar("global map", [&] { return buildGlobalMap(graph, args.params.global); });

  // --grid: computed before anything is written (a grid the map cannot give fails the run with
  // nothing written), written into DIR once the export is in place.
  std::optional<OccupancyGrid> grid;
  if (args.grid_resolution_m > 0) {
    OccupancyGridSpec spec;
    spec.resolution_m = args.grid_resolution_m;
    std::tie(spec.band_lo_m, spec.band_hi_m) = parseGridBand(args.grid_band);
    spec.up = parseUpAxis(args.grid_up);
    QueryParams query;
    query.threads = args.params.global.threads;
    grid = withStageBar("occupancy grid", [&] {
      const QueryMap map = graph.size() ? QueryMap::build(graph, global, query) : QueryMap();
      if (const std::string note = gridBandClipNote(spec, layOutOccupancyGrid(map, spec), "--grid-band"); !note.empty())
        std::fprintf(stderr, "vdmap map: note: %s\n", note.c_str());
      return computeOccupancyGrid(map, spec);
    });
  }
  // --mesh: computed before anything is written, like the grid.
  std::optional<ColoredTriangleMesh> mesh;
  if (args.mesh) {
    MeshParams mesh_params = args.mesh_options.over({});
    mesh_params.model = args.params.global.filter.model;
    mesh_params.threads = args.params.global.threads;
    mesh = withStageBar("mesh", [&] { return buildSurfaceMesh(graph, global.kept, mesh_params); });
    if (mesh->triangles.empty())
      std::fprintf(stderr, "vdmap map: note: the map has no surface to mesh: the mesh is empty\n");
  }
  if (!args.json) printKeyframeTable(graph, global);
  MapExportOptions options;
  options.octomap_resolution_m = args.octomap_resolution_m;
  options.trajectory = mapper.trajectory();
  options.run_stats = runStats(mapper, seq, frames_loaded, times, refined, options.trajectory);
  options.run_stats.update(frameCounts(seq));
  options.run_stats.update(provenanceStats({seq.folder().string(), seq.cameraSource(), seq.camera(),
                                            mapper.params().poses, refinement(args.sequence), args.params}));
  // Once the export is staged and before it is put in place: a run that fails keeps neither.
  if (!args.save.empty())
    options.before_commit = [&] {
      withStageBar("session file",
                   [&] { saveSession(args.save, graph, sessionInfo(mapper, args.params.global, seq.folder())); });
    };
  const nlohmann::json stats = exportWithProgress(args.out, graph, global, options);
  if (grid) writeOccupancyGrid(std::filesystem::path(args.out) / "grid.yaml", *grid);
  if (mesh) writeMeshPly(std::filesystem::path(args.out) / "global_mesh.ply", *mesh);
  if (args.json) {
    std::cout << jsonText(stats) << "\n";
    return;
  }
  printSummary(mapper, global, times, args.out);
  if (mapper.params().poses == PoseSource::kTrack) printTrackingSummary(mapper, refined, stats);
}

}  // namespace

void addMapCommand(CLI::App& app) {
  auto* verb = app.add_subcommand("map", "Map a sequence: keyframes with local maps, covisibility graph, global map");
  auto args = std::make_shared<MapArgs>();
  addSequenceArgs(*verb, args->sequence);
  addPoseSourceArg(*verb, args->sequence);
  addRefineArg(*verb, args->sequence);
  verb->add_option("--out", args->out,
                   "output folder (created if missing): local_maps.ply, keyframes.txt, trajectory.txt, graph.txt, "
                   "global_points.ply, global_ellipsoids.ply, global_gaussians.ply, [global.bt], stats.json")
      ->required();
  verb->add_option("--save", args->save, "also save the whole session (a .vdmap file, docs/vdmap-format.md)");
  verb->add_option("--load", args->load,
                   "continue a saved session (.vdmap) on SEQ where it stopped: its keyframes, graph, parameters and "
                   "state; --frames defaults to the frames after its last one (save the result with --save)");
  verb->add_option("--octomap", args->octomap_resolution_m,
                   "also write global.bt, an OctoMap of this resolution (m, > 0 and at most 1) sampled from the "
                   "global map; the map must fit in OctoMap's 16-bit keys (32767 voxels each way from the origin)")
      ->check(octomapResolutionCheck());
  // point queries (docs/method.md 13): the occupancy grid planners read, as `vdmap query --op grid`
  auto* grid =
      verb->add_option("--grid", args->grid_resolution_m,
                       "also write grid.pgm + grid.yaml, a ROS map_server occupancy grid of this cell size (m) "
                       "of the --grid-band height band (vdmap query --op grid)")
          ->check(positiveFiniteCheck());
  auto* band = verb->add_option("--grid-band", args->grid_band, "the grid's height band LO:HI (m along --grid-up)")
                   ->check(parsedBy(parseGridBand, "LO:HI"));
  verb->add_option("--grid-up", args->grid_up, "the axis the grid's band runs along")
      ->check(CLI::IsMember({"+z", "-z", "+y", "-y", "+x", "-x"}))
      ->capture_default_str()
      ->needs(grid);
  grid->needs(band);
  band->needs(grid);
  auto* mesh = verb->add_flag("--mesh", args->mesh,
                              "also write global_mesh.ply, a triangle mesh of the local maps (vdmap mesh)");
  addMeshOptions(*verb, args->mesh_options);
  for (const char* name :
       {"--mesh-max-slope", "--mesh-edge-sigma", "--mesh-stride", "--mesh-no-fuse", "--max-triangles"})
    verb->get_option(name)->needs(mesh);
  verb->add_flag("--json", args->json, "print stats.json to stdout instead of the table");
  addParameterOptions(*verb, args->params);
  verb->add_option("--threads", args->params.global.threads,
                   "global-map threads, 0.." + std::to_string(kMaxThreads) +
                       " (0: all; more than the machine has run as many as it has); the map does not depend on it")
      ->check(CLI::Range(0, kMaxThreads))
      ->capture_default_str();
  verb->callback([args] { runMap(*args); });
}

}  // namespace vdmap::app
