// vdmap bench SEQ: the paper's comparison (docs/method.md 12) on the same frames in one
// process: vdmap's local-map update and whole pipeline, OctoMap at 0.10/0.05/0.02 m, the NDT-OM
// baseline at 0.10 m and Open3D's TSDF at 0.02/0.01 m (when its plugin is built). Frames are
// decoded once, before any timing; each method runs over all frames in its own pass, so none
// pays for another's cache pollution. Times are the process's CPU time per frame (cpuTimeMs),
// so a busy machine does not skew the ratios; the pipeline's stage split is the Mapper's own
// wall-clock report. Single-threaded throughout (liboctomap on Debian has no
// OpenMP, the integrator is sequential, the Open3D plugin pins OpenMP to one thread).
// With --mesh every method's map is also scored against the reference (docs/method.md 12).
// With --poses track the odometry peers (app/bench/odometry_peers.h) estimate the poses of the same
// frames: CPU ms per frame and ATE against the sequence's ground truth of each.
// Each method's timing loop is in app/bench/ (one file per method, the report in bench_report.cpp).
// The other modes: --long (a whole sequence mapped), --query (the point queries, against
// OctoMap), --view (the 3-D view's frame times on a saved map), --suite (a render suite's
// stages) and --ellipsoids (the ellipsoid renderer).
#include <algorithm>
#include <filesystem>
#include <limits>
#include <optional>
#include <set>
#include <stdexcept>

#include "app/bench/bench_long.h"
#include "app/bench/bench_method.h"
#include "app/bench/bench_report.h"
#include "app/bench/ellipsoid_timing.h"
#include "app/bench/ndt_om_timing.h"
#include "app/bench/octomap_timing.h"
#include "app/bench/odometry_timing.h"
#include "app/bench/query_timing.h"
#include "app/bench/suite_timing.h"
#include "app/bench/surface_timing.h"
#include "app/bench/tsdf_timing.h"
#include "app/bench/vdmap_timing.h"
#include "app/bench/view_timing.h"
#include "app/cli/command_line.h"
#include "app/cli/sequence_args.h"
#include "app/verbs.h"
#include "app/view/progress.h"
#include "app/view/render_view.h"
#include "mapping/core/timing.h"
#include "mapping/files/map_export.h"
#include "mapping/files/ply_reader.h"

namespace vdmap::app {
namespace {

// --long: every frame unless --frames says otherwise, never all decoded at once.
void runLongRun(BenchArgs args) {
  const std::filesystem::path out_dir = args.out;
  checkExportFolder(out_dir);
  MapperParams mapper;
  mapper.local_map = args.local_map;
  mapper.poses = args.poses == "track" ? PoseSource::kTrack : PoseSource::kGroundTruth;
  checkRefinementApplies(args.sequence, mapper.poses);
  args.long_options.json = args.json;
  const Sequence seq = openSequence(args.sequence);
  noteCameraGuess(seq, "bench");
  runLongBench(seq, mapper, {}, out_dir, args.long_options, refinement(args.sequence));
}

// Decoded on this thread, each frame timed (into `decode_ms`): decoding is the prefetch thread's
// share of the pipeline's throughput.
std::vector<RgbdFrame> decodeFrames(const Sequence& seq, std::vector<double>* decode_ms) {
  std::vector<RgbdFrame> decoded;
  ProgressBar progress("decoding", seq.size());
  for (std::size_t i = 0; i < seq.size(); ++i) {
    decode_ms->push_back(cpuTimeMs([&] { decoded.push_back(seq.load(i)); }));
    progress.update(decoded.size());
  }
  return decoded;
}

// The peers' rows: OctoMap at 0.10/0.05/0.02 m, the NDT-OM baseline at 0.10 m, Open3D's TSDF at
// 0.02/0.01 m (a peer the options skip gets a row that says so).
std::vector<MethodResult> peerRows(const BenchInput& in) {
  std::vector<MethodResult> rows;
  for (const double res : {0.10, 0.05, 0.02})
    rows.push_back(in.args.no_octomap ? peerRow("OctoMap", "octomap", res, "--no-octomap") : timeOctomap(in, res));
  rows.push_back(timeNdtOm(in, 0.10));
  for (const double voxel : {0.02, 0.01})
    rows.push_back(in.args.no_open3d ? peerRow("Open3D TSDF", "open3d_tsdf", voxel, "--no-open3d")
                                     : timeOpen3dTsdf(in, voxel));
  return rows;
}

// vdmap's update, its pipeline with the global map of the keyframes it made (its ellipsoid means
// are vdmap's map elements), then the peers; with --poses track the tracking rows.
void measure(const BenchInput& in, const std::filesystem::path& out_dir, BenchFigures* f) {
  f->update = timeVdmapUpdate(in);
  Mapper mapper(in.cam, pipelineParams(in.args));
  f->pipeline = timeVdmapPipeline(in, &mapper);
  f->global = buildGlobalMap(mapper.graph(), {});
  f->global_stats = globalMapStats(mapper.graph(), f->global);
  f->revisits = mapper.revisits();
  f->keyframes = mapper.graph().size();
  f->rows = vdmapRows(in, median(f->update.ms), median(f->pipeline.total_ms), f->global);
  f->first_peer = f->rows.size();
  for (MethodResult& row : peerRows(in)) f->rows.push_back(std::move(row));
  if (in.args.poses == "track") f->tracking = timeTracking(in, out_dir);
}

// A mode that times the renderer or the 3-D view takes only its own options (and --json): any
// other given with it would be ignored, so it is refused as CLI11 refuses excluded options.
void checkModeOptions(const CLI::App& verb, const std::string& mode, const std::set<std::string>& own) {
  for (const CLI::Option* option : verb.get_options()) {
    const std::string name = option->get_name();
    if (option->count() > 0 && name != mode && name != "--json" && own.count(name) == 0)
      throw CLI::ExcludesError(mode, name);
  }
}

void runBench(const CLI::App& verb, BenchArgs args) {
  if (args.ellipsoids > 0) {
    checkModeOptions(verb, "--ellipsoids", {"--size", "--points-below", "--sphere-level", "--png"});
    return runEllipsoidBench(args.ellipsoids, args.sphere_level, args.draw, args.json);
  }
  if (!args.suite.empty()) {
    checkModeOptions(verb, "--suite", {"--runs"});
    return runSuiteBench(args.suite, args.runs, args.json);
  }
  if (args.view) {
    checkModeOptions(verb, "--view",
                     {"SEQ", "--size", "--points-below", "--png", "--replicate", "--steps", "--zoom", "--fast-budget"});
    if (args.sequence.folder.empty()) throw CLI::RequiredError("SEQ (a saved session or map)");
    return runViewBench(args.sequence.folder, args.view_options, args.draw, args.json);
  }
  for (const char* name : {"--size", "--points-below", "--png"})
    if (verb.count(name) > 0) throw CLI::RequiresError(name, "--view or --ellipsoids");
  if (args.sequence.folder.empty()) throw CLI::RequiredError("SEQ");
  if (args.long_run) return runLongRun(std::move(args));
  if (args.query) return runQueryBench(args, args.out);
  checkRefinementApplies(args.sequence, args.poses == "track" ? PoseSource::kTrack : PoseSource::kGroundTruth);
  // Frames are held decoded, so the default is a short range: 0:30, or the whole sequence when
  // it is shorter (a range typed past the end is an error, as everywhere).
  const bool default_range = args.sequence.frames.empty();
  if (default_range) args.sequence.frames = "0:30";
  // Like map --out: created if missing (checked now, before any work).
  const std::filesystem::path out_dir = args.out;
  checkExportFolder(out_dir);
  std::optional<ColoredTriangleMesh> mesh;
  if (!args.mesh.empty()) mesh = readPlyMesh(args.mesh);  // fail before any work on a bad mesh
  const Sequence seq = openSequence(args.sequence, default_range);
  noteCameraGuess(seq, "bench");
  const PinholeCamera& cam = seq.camera();
  for (const int s : args.accuracy_cell_sizes)
    if (s > std::min(cam.width, cam.height))
      throw std::invalid_argument("--accuracy-cell-sizes: cell size " + std::to_string(s) + " px is larger than the " +
                                  std::to_string(cam.width) + "x" + std::to_string(cam.height) + " image");

  BenchFigures figures;
  figures.frame_range = frameRangeText(seq.frameRange());
  figures.width = cam.width, figures.height = cam.height;
  figures.mesh_scored = mesh.has_value();
  const std::vector<RgbdFrame> decoded = decodeFrames(seq, &figures.decode_ms);
  figures.frames = decoded.size();
  if (args.surfaces) return runSurfaceBench({decoded, cam, args, mesh ? &*mesh : nullptr}, out_dir);
  measure({decoded, cam, args, mesh ? &*mesh : nullptr}, out_dir, &figures);
  writeBenchReport(figures, args, out_dir);
}

}  // namespace

// The comparison's options (the default mode); returns --mesh, which --query takes too.
CLI::Option* addComparisonOptions(CLI::App& verb, BenchArgs& args) {
  verb.add_option("--keyframe-every", args.keyframe_every,
                  "the update row starts a keyframe every N frames (the pipeline row decides its own keyframes)")
      ->check(CLI::Range(1, std::numeric_limits<int>::max()))
      ->capture_default_str();
  verb.add_option("--cell-size", args.local_map.cell_size_px, "container cell size, px")
      ->check(CLI::Range(1, std::numeric_limits<int>::max()))
      ->capture_default_str();
  // Whether the mesh exists is a question about a file: read (and refused) before any work.
  auto* mesh = verb.add_option("--mesh", args.mesh,
                               "reference mesh PLY (world frame of the poses): adds every method's accuracy");
  verb.add_option("--accuracy-cell-sizes", args.accuracy_cell_sizes,
                  "with --mesh, also score vdmap at these cell sizes, px (e.g. 3,5,9,15)")
      ->delimiter(',')
      ->check(CLI::Range(1, std::numeric_limits<int>::max()))
      ->needs(mesh);
  verb.add_flag("--surfaces", args.surfaces,
                "the surface meshes instead: vdmap's (vdmap mesh) and Open3D's TSDF meshes at 0.02 and 0.01 m of the "
                "same frames, written to --out, timed, and with --mesh scored with the same sampler (median, p95, "
                "completion within 2 cm)");
  verb.add_option("--samples", args.completion_samples, "mesh samples for completion")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, AccuracyParams::kMaxCompletionSamples));
  verb.add_option("--out", args.out, "folder for bench.json and bench.md")->capture_default_str();
  verb.add_flag("--no-octomap", args.no_octomap, "skip the OctoMap peers (for profiling; with --query: vdmap alone)");
  verb.add_flag("--no-open3d", args.no_open3d, "skip the Open3D peers (TSDF, and odometry with --poses track)");
  verb.add_option("--poses", args.poses,
                  "gt: map with the sequence's ground-truth poses; track: also track the poses with vdmap (with and "
                  "without loop closure) and the odometry peers (OpenCV RgbdOdometry and ICPOdometry frame to frame "
                  "and against keyframes, Open3D's hybrid odometry) on the same frames: ms per frame and ATE "
                  "against the ground truth, and trajectory_<method>.txt in --out")
      ->capture_default_str()
      ->check(CLI::IsMember({"gt", "track"}));
  return mesh;
}

// --long and its options; returns --long.
CLI::Option* addLongRunOptions(CLI::App& verb, BenchArgs& args) {
  addRefineArg(verb, args.sequence);
  auto* long_run = verb.add_flag(
      "--long", args.long_run,
      "the long run instead: every frame (or --frames) mapped as `vdmap map` does, the mapping thread's CPU time per "
      "frame, resident memory, live heap, keyframes and the global map's size into long.csv and long.json; with "
      "--poses track the poses are tracked (and refined as --refine says) and long.json adds frames lost, loop "
      "closures and the ATE");
  verb.add_option("--global-every", args.long_options.global_every, "with --long: frames between global-map builds")
      ->check(CLI::Range(1, std::numeric_limits<int>::max()))
      ->needs(long_run)
      ->capture_default_str();
  return long_run;
}

void addQueryOptions(CLI::App& verb, BenchArgs& args, CLI::Option* mesh, CLI::Option* long_run) {
  // --query: the point queries (docs/method.md 13) against OctoMap and ground truth.
  auto* query = verb.add_flag(
      "--query", args.query,
      "the point queries instead: map every frame (or --frames) with vdmap (gt poses) and OctoMap 0.05/0.02 m, then "
      "time classify, distance and castView against OctoMap search/castRay (one thread, CPU, medians of 3), then "
      "vdmap alone: classify under each conflict rule, distance near surfaces and in open space, castRays, memory by "
      "part; with --mesh and --truth also their accuracy against ground truth");
  query->excludes(long_run);
  verb.add_option("--truth", args.truth,
                  "with --query and --mesh: the same poses rendered without noise (vdmap synth --noise none)")
      ->needs(query)
      ->needs(mesh);
  verb.add_option("--truth-points", args.truth_points,
                  "with --truth: occupied, free and unknown points scored each (free near the surface: half as many)")
      ->needs(query)
      ->check(CLI::Range(std::size_t{2}, std::size_t{10'000'000}))
      ->capture_default_str();
  verb.add_option("--query-points", args.query_points, "with --query: points classified per pass")
      ->needs(query)
      ->check(CLI::Range(std::size_t{1}, std::size_t{100'000'000}))
      ->capture_default_str();
  verb.add_option("--octomap-every", args.octomap_every,
                  "with --query: frames between OctoMap insertions (default: ceil(frames / 500))")
      ->needs(query)
      ->check(CLI::Range(1, std::numeric_limits<int>::max()));
  verb.add_option("--views", args.views,
                  "with --query: castView poses (keyframes spread over the map; 0: no views timed)")
      ->needs(query)
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
}

// --view, --suite and --ellipsoids, and the drawing options they share.
void addDrawingOptions(CLI::App& verb, BenchArgs& args) {
  // The renderer and the 3-D view (docs/performance.md "Rendering" and "Workbench").
  auto* view = verb.add_flag(
      "--view", args.view,
      "the 3-D view's frame times instead, offscreen: SEQ is a saved session or map (anything render --map opens), "
      "its global map drawn along --steps orbit steps at full quality and with the fast pass, then the settle frame "
      "and a cached frame; medians, wall clock (glFinish) and process CPU");
  verb.add_option("--replicate", args.view_options.replicate,
                  "with --view: N copies of the map side by side along x (for paper-scale maps)")
      ->needs(view)
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  verb.add_option("--steps", args.view_options.steps, "with --view: orbit steps, 0.03 rad apart")
      ->needs(view)
      ->check(CLI::Range(2, 100000))
      ->capture_default_str();
  verb.add_option("--zoom", args.view_options.zoom,
                  "with --view: the orbit's distance over the framed one (below 1: inside the map)")
      ->needs(view)
      ->check(CLI::Range(0.01f, 100.f))
      ->capture_default_str();
  verb.add_option("--fast-budget", args.view_options.fast_budgets,
                  "with --view: the fast pass's size, K ellipsoids (repeatable; default 50000, 100000, 200000, 400000)")
      ->needs(view)
      ->check(CLI::Range(std::size_t{1}, std::size_t{1'000'000'000}));
  auto* suite =
      verb.add_option(
              "--suite", args.suite,
              "the speed of render --suite instead (no SEQ): FILE is a render suite (views.yaml; its goldens must exist) or "
              "a session (.vdmap: a suite of 20 views of it is written to a temporary folder and its goldens made first); "
              "--runs comparing runs in this process, the medians of each stage")
          ->type_name("FILE");
  verb.add_option("--runs", args.runs, "with --suite: comparing runs (and session loads)")
      ->needs(suite)
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  auto* ellipsoids = verb.add_option(
      "--ellipsoids", args.ellipsoids,
      "the ellipsoid renderer alone instead (no SEQ): N random instanced ellipsoids drawn offscreen at --size "
      "(default 1280x720); prints the upload and the median of 5 frames (wall clock, glFinish)");
  ellipsoids->check(CLI::Range(1, 100'000'000));
  verb.add_option("--sphere-level", args.sphere_level,
                  "with --ellipsoids: icosphere subdivisions of one ellipsoid (0..3; default 1)")
      ->needs(ellipsoids)
      ->check(CLI::Range(0, 3));
  verb.add_option("--size", args.draw.size,
                  "with --view or --ellipsoids: image size WIDTHxHEIGHT (default 752x870, the 3-D viewport of a "
                  "1600x900 window, with --view)")
      ->check(parsedBy(parseViewSize, "WxH"));
  verb.add_option("--points-below", args.draw.points_below,
                  "with --view or --ellipsoids: draw ellipsoids projecting to a radius below this many pixels as "
                  "flat splats (0: never; default 4)")
      ->check(CLI::Range(0.f, 64.f));
  verb.add_option("--png", args.draw.png,
                  "with --view or --ellipsoids: write the last frames, to look at: PREFIX_full.png and "
                  "PREFIX_fast_K.png (--view), PREFIX.png (--ellipsoids)")
      ->type_name("PREFIX");
}

void addBenchCommand(CLI::App& app) {
  auto* verb = app.add_subcommand(
      "bench",
      "Compare vdmap with OctoMap, NDT-OM and Open3D's TSDF on the same frames, or time its point queries, the "
      "3-D view, render suites or the ellipsoid renderer");
  auto args = std::make_shared<BenchArgs>();
  addSequenceArgs(*verb, args->sequence);
  verb->get_option("SEQ")->required(false)->description(
      "the sequence (a folder of any layout vdmap reads, a ROS 1 bag or an MCAP file: docs/cli.md, Sequences); "
      "with --view a saved session or map file; none with --suite or --ellipsoids");
  verb->get_option("--frames")
      ->description(
          "frames A:B of the depth list; a plain N means 0:N (default 0:30, or fewer when the sequence is "
          "shorter); a range past the end is an error. Frames are held decoded in memory, ~1.5 MB each at 640x480");
  CLI::Option* mesh = addComparisonOptions(*verb, *args);
  CLI::Option* long_run = addLongRunOptions(*verb, *args);
  addQueryOptions(*verb, *args, mesh, long_run);
  addDrawingOptions(*verb, *args);
  verb->add_flag("--json", args->json, "print JSON instead of text");
  verb->callback([args, verb] { runBench(*verb, *args); });
}

}  // namespace vdmap::app
