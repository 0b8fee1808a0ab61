// vdmap query S.vdmap --op OP --out FILE: the point queries a planner asks of the view-dependent
// map (docs/method.md 13) from the command line: occupied / free / unknown, distance to the
// nearest surface, collision of bodies of spheres, ray casts, and the exports planners read (a
// ROS map_server occupancy grid of a height band, an OctoMap .bt whose free space is the
// keyframes' own). The session's global map is rebuilt with its own parameters, after
// --keyframe-poses when given (corrected poses move the answers without re-integration).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <numeric>

#include <nlohmann/json.hpp>

#include "app/cli/command_line.h"
#include "app/query_files/query_io.h"
#include "app/verbs.h"
#include "app/view/progress.h"
#include "mapping/core/error.h"
#include "mapping/core/parallel.h"
#include "mapping/core/timing.h"
#include "mapping/files/occupancy_grid.h"
#include "mapping/files/octomap_export.h"
#include "mapping/files/session_file.h"
#include "mapping/global_map/global_map.h"
#include "mapping/io/json_text.h"
#include "render/map_scene.h"

namespace vdmap::app {
namespace {

namespace fs = std::filesystem;

struct QueryArgs {
  std::string map;
  std::string op;
  std::string out;
  std::string points;
  bool json = false;
  int keyframe = -1;
  double clearance_m = 0.0;
  double max_range_m = 8.0;
  double max_distance_m = INFINITY;
  std::string conflict = "occupied";
  std::string keyframe_poses;
  double resolution_m = 0.05;
  std::string band;
  std::string up = "+z";
  QueryParams params;
};

// More records than this show a progress bar.
constexpr std::size_t kProgressAbove = 100000;

ConflictRule conflictRule(const std::string& name) {
  if (name == "recent") return ConflictRule::kRecent;
  if (name == "precise") return ConflictRule::kPrecise;
  return ConflictRule::kOccupied;
}

// The command line by itself (CLI11's codes, before any work): which options go with which op,
// and the --out extension the op writes.
void checkQueryArgs(const QueryArgs& args, QueryOp op, const CLI::App& verb) {
  const auto given = [&verb](const char* name) { return verb.get_option(name)->count() > 0; };
  if (queryOpReadsPoints(op) && args.points.empty())
    throw CLI::RequiredError("--op " + args.op + " needs --points FILE (.txt or .ply)", CLI::ExitCodes::RequiredError);
  const auto only = [&](const char* option, bool applies, const char* ops) {
    if (given(option) && !applies)
      throw CLI::ValidationError(option, std::string("applies to --op ") + ops + " only, not --op " + args.op);
  };
  only("--points", queryOpReadsPoints(op), "classify, distance, collide and ray");
  only("--keyframe", op == QueryOp::kClassify, "classify");
  only("--clearance", op == QueryOp::kCollide, "collide");
  only("--max-range", op == QueryOp::kRay, "ray");
  only("--max-distance", op == QueryOp::kDistance, "distance");
  only("--resolution", op == QueryOp::kGrid || op == QueryOp::kOctomap, "grid and octomap");
  only("--band", op == QueryOp::kGrid, "grid");
  only("--up", op == QueryOp::kGrid, "grid");
  if (op == QueryOp::kGrid && args.band.empty())
    throw CLI::RequiredError("--op grid needs --band LO:HI (the height band, m along --up)",
                             CLI::ExitCodes::RequiredError);
  const std::string ext = fs::path(args.out).extension().string();
  const char* wanted = op == QueryOp::kGrid ? ".yaml" : op == QueryOp::kOctomap ? ".bt" : nullptr;
  if (wanted ? ext != wanted : (ext != ".txt" && ext != ".ply"))
    throw CLI::ValidationError("--out", "'" + args.out + "': --op " + args.op + " writes " +
                                            (wanted ? std::string(wanted) : std::string(".txt or .ply")) +
                                            " (the format follows the extension)");
}

// keyframe_rank for ConflictRule::kRecent: keyframes ordered by the last frame placed in them.
std::vector<int> lastObservedRank(const Session& session) {
  const KeyframeGraph& graph = session.graph;
  std::vector<long long> last(graph.size());
  for (std::size_t k = 0; k < graph.size(); ++k) last[k] = graph.keyframe(static_cast<int>(k)).frame_index;
  for (const FramePose& f : session.info.state.frame_poses)
    if (f.keyframe >= 0 && static_cast<std::size_t>(f.keyframe) < last.size())
      last[static_cast<std::size_t>(f.keyframe)] =
          std::max<long long>(last[static_cast<std::size_t>(f.keyframe)], f.frame_index);
  std::vector<int> order(graph.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&last](int a, int b) {
    return last[static_cast<std::size_t>(a)] != last[static_cast<std::size_t>(b)]
               ? last[static_cast<std::size_t>(a)] < last[static_cast<std::size_t>(b)]
               : a < b;
  });
  std::vector<int> rank(graph.size());
  for (std::size_t r = 0; r < order.size(); ++r) rank[static_cast<std::size_t>(order[r])] = static_cast<int>(r);
  return rank;
}

struct LoadedMap {
  QueryMap map;
  std::size_t keyframes = 0;
  std::size_t ellipsoids = 0;
  int poses_matched = -1;                              ///< keyframes --keyframe-poses moved (-1: not given)
  Eigen::Vector3d data_up = Eigen::Vector3d::UnitZ();  ///< the session's estimated up (render::estimateUp)
  double load_ms = 0, build_ms = 0;
};

LoadedMap loadQueryMap(const QueryArgs& args) {
  if (!isSessionPath(args.map)) {
    if (!fs::exists(args.map))
      throw InputError(args.map, "no such session file (expected a .vdmap session: vdmap map --save)");
    throw InputError(args.map,
                     std::string(fs::is_directory(args.map) ? "a folder, " : "") +
                         "not a session: vdmap query reads a session file (.vdmap, written by vdmap map --save)");
  }
  LoadedMap loaded;
  const auto start = std::chrono::steady_clock::now();
  SessionDecodeOptions decode;
  decode.decode_images = false;  // the queries need the local maps and poses, not the images
  decode.keep_images = false;
  decode.keep_features = false;
  Session session = loadSession(args.map, decode);
  if (!args.keyframe_poses.empty())
    loaded.poses_matched = applyTrajectoryFile(session.graph, args.keyframe_poses).matched;
  loaded.load_ms = msSince(start);
  loaded.keyframes = session.graph.size();
  if (args.keyframe >= 0 && static_cast<std::size_t>(args.keyframe) >= session.graph.size())
    throw InputError(args.map,
                     "--keyframe " + std::to_string(args.keyframe) + ": the session has " +
                         counted(static_cast<long long>(session.graph.size()), "keyframe") +
                         (session.graph.size() ? " (0.." + std::to_string(session.graph.size() - 1) + ")" : ""));
  const auto build_start = std::chrono::steady_clock::now();
  if (session.graph.size() > 0) {
    GlobalMapParams global = session.info.global;
    global.threads = args.params.threads;
    const GlobalMap map = withStageBar("global map", [&] { return buildGlobalMap(session.graph, global); });
    const std::vector<int> rank = lastObservedRank(session);
    loaded.map = withStageBar("query map", [&] { return QueryMap::build(session.graph, map, args.params, rank); });
    // The up the window and `vdmap render` estimate for this session: its cameras and floor.
    const glm::vec3 up = render::estimateUp(
        render::graphSceneOf(session.graph, session.info.state, session.info.camera, false).trajectory, map.ellipsoids);
    loaded.data_up = Eigen::Vector3d(up.x, up.y, up.z);
  }
  loaded.ellipsoids = loaded.map.ellipsoids();
  loaded.build_ms = msSince(build_start);
  return loaded;
}

// Asks the map about every record of --points a batch at a time, writes the answers, and
// returns the summary's figures.
nlohmann::json runPointQuery(const QueryArgs& args, QueryOp op, const QueryMap& map, std::size_t records) {
  PointQueryOptions options;
  options.keyframe = args.keyframe;
  options.clearance_m = args.clearance_m;
  options.max_range_m = args.max_range_m;
  options.max_distance_m = args.max_distance_m;
  std::unique_ptr<ProgressBar> bar;
  if (records > kProgressAbove) bar = std::make_unique<ProgressBar>(queryOpName(op), records);
  return answerQueryRecords(map, op, args.points, records, args.out, options, [&bar](std::size_t done, std::size_t) {
    if (bar) bar->update(done);
  });
}

// The degrees between unit vectors a and b.
double degreesBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.dot(b), -1.0, 1.0)) * 180.0 / M_PI;
}

nlohmann::json runGrid(const QueryArgs& args, const QueryMap& map, const Eigen::Vector3d& data_up) {
  OccupancyGridSpec spec;
  spec.resolution_m = args.resolution_m;
  std::tie(spec.band_lo_m, spec.band_hi_m) = parseGridBand(args.band);
  // "data": the axis nearest the session's estimated up. A band along an axis far from that up
  // slices the room askew: say so, and which axis would not.
  UpAxis nearest = UpAxis::kPlusZ;
  double nearest_deg = 180.0;
  for (const UpAxis axis :
       {UpAxis::kPlusZ, UpAxis::kMinusZ, UpAxis::kPlusY, UpAxis::kMinusY, UpAxis::kPlusX, UpAxis::kMinusX}) {
    Eigen::Vector3d u, v, w;
    gridAxes(axis, &u, &v, &w);
    if (const double deg = degreesBetween(w, data_up); deg < nearest_deg) nearest = axis, nearest_deg = deg;
  }
  spec.up = args.up == "data" ? nearest : parseUpAxis(args.up);
  // Clipped, or refused (outside the map, too many points to ask) in one line before any query.
  const std::string clip_note = gridBandClipNote(spec, layOutOccupancyGrid(map, spec), "--band");
  if (!clip_note.empty()) std::fprintf(stderr, "vdmap query: note: %s\n", clip_note.c_str());
  Eigen::Vector3d u, v, w;
  gridAxes(spec.up, &u, &v, &w);
  const double off_deg = degreesBetween(w, data_up);
  if (args.up == "data")
    std::fprintf(stderr,
                 "vdmap query: note: grid up %s, the axis nearest the session's estimated up (%.2f, %.2f, %.2f), "
                 "%.1f degrees from it\n",
                 upAxisName(spec.up), data_up.x(), data_up.y(), data_up.z(), off_deg);
  else if (off_deg > 20.0 && spec.up != nearest)
    std::fprintf(stderr,
                 "vdmap query: note: grid up %s is %.0f degrees from the session's estimated up (%.2f, %.2f, %.2f); "
                 "--up %s (or data) is %.1f degrees from it\n",
                 upAxisName(spec.up), off_deg, data_up.x(), data_up.y(), data_up.z(), upAxisName(nearest), nearest_deg);
  const auto start = std::chrono::steady_clock::now();
  std::unique_ptr<ProgressBar> bar;
  const OccupancyGrid grid = computeOccupancyGrid(map, spec, [&bar](std::size_t done, std::size_t total) {
    if (!bar) bar = std::make_unique<ProgressBar>("grid", total);
    bar->update(done);
  });
  bar.reset();
  const double ms = msSince(start);
  writeOccupancyGrid(args.out, grid);
  return {{"width", grid.width},
          {"height", grid.height},
          {"resolution_m", grid.resolution_m},
          {"origin_m", {rounded6(grid.origin_m.x()), rounded6(grid.origin_m.y())}},
          {"up", upAxisName(grid.up)},
          {"occupied", grid.occupied},
          {"free", grid.free},
          {"unknown", grid.unknown},
          {"samples", grid.samples},
          {"query_ms", rounded6(ms)},
          {"records_per_s", ms > 0 ? std::round(1e3 * static_cast<double>(grid.samples) / ms) : 0.0}};
}

nlohmann::json runOctomap(const QueryArgs& args, const QueryMap& map) {
  std::unique_ptr<ProgressBar> bar;
  const QueryOctomapReport r =
      writeOctomapBtFromQuery(args.out, map, args.resolution_m, [&bar](std::size_t done, std::size_t total) {
        if (!bar) bar = std::make_unique<ProgressBar>("OctoMap", total);
        bar->update(done);
      });
  bar.reset();
  const double ms = 1e3 * r.seconds;
  return {{"resolution_m", args.resolution_m},
          {"voxels", r.voxels},
          {"occupied_voxels", r.occupied_voxels},
          {"free_voxels", r.free_voxels},
          {"leaves", r.leaves},
          {"query_ms", rounded6(ms)},
          {"records_per_s", ms > 0 ? std::round(1e3 * static_cast<double>(r.voxels) / ms) : 0.0}};
}

void printSummary(QueryOp op, const nlohmann::json& s, const std::string& out) {
  const auto count = [&s](const char* key) { return s[key].get<long long>(); };
  const auto of = [&count](const char* key, const char* noun, const char* plural = "") {
    return counted(count(key), noun, plural);
  };
  // To the millimetre, every digit: 123456000 m is not cut to "12345600".
  const auto metres = [&s](const char* key) {
    return s[key].is_null() ? std::string("none") : shortNumber(std::round(s[key].get<double>() * 1e3) / 1e3) + " m";
  };
  switch (op) {
    case QueryOp::kClassify:
      std::printf("classify %s%s: %lld occupied, %lld free, %lld unknown", of("records", "point").c_str(),
                  s.contains("keyframe") ? (" in keyframe " + std::to_string(s["keyframe"].get<int>())).c_str() : "",
                  count("occupied"), count("free"), count("unknown"));
      break;
    case QueryOp::kDistance:
      std::printf("distance of %s: min %s, median %s, %lld inside a surface's gate", of("records", "point").c_str(),
                  metres("min_m").c_str(), metres("median_m").c_str(), count("inside"));
      break;
    case QueryOp::kCollide:
      std::printf("collide %s in %s: %lld colliding, %lld touching unknown space, min clearance %s",
                  of("records", "sphere").c_str(), of("bodies", "body").c_str(), count("colliding"),
                  count("touching_unknown"), metres("min_clearance_m").c_str());
      break;
    case QueryOp::kRay:
      std::printf("ray %s: %s, %s, median range %s", of("records", "ray").c_str(), of("hits", "hit").c_str(),
                  of("misses", "miss").c_str(), metres("median_t_m").c_str());
      break;
    case QueryOp::kGrid:
      std::printf("grid %d x %d cells of %g m (up %s): %lld occupied, %lld free, %lld unknown; %s",
                  s["width"].get<int>(), s["height"].get<int>(), s["resolution_m"].get<double>(),
                  s["up"].get<std::string>().c_str(), count("occupied"), count("free"), count("unknown"),
                  of("samples", "sample").c_str());
      break;
    case QueryOp::kOctomap:
      std::printf("octomap of %g m: %s asked, %lld occupied, %lld free, %s after pruning",
                  s["resolution_m"].get<double>(), of("voxels", "voxel").c_str(), count("occupied_voxels"),
                  count("free_voxels"), of("leaves", "leaf", "leaves").c_str());
      break;
  }
  std::printf("; %.1f ms (%.3g per s) -> %s\n", s["query_ms"].get<double>(), s["records_per_s"].get<double>(),
              out.c_str());
}

void runQuery(QueryArgs args, const CLI::App& verb) {
  const QueryOp op = parseQueryOp(args.op);
  checkQueryArgs(args, op, verb);
  args.params.conflict = conflictRule(args.conflict);
  // Outputs that cannot be written and inputs that are wrong fail before the map is loaded.
  checkOutputFile(args.out, "--out");
  checkNotAnInput(args.out, "--out", {{"--points", args.points}, {"MAP", args.map}});
  // Every record is checked (and counted) before the map is loaded; the answers read them again.
  const std::size_t records = queryOpReadsPoints(op) ? countQueryRecords(args.points, op, args.max_range_m) : 0;
  const LoadedMap loaded = loadQueryMap(args);
  nlohmann::json summary = {{"map", args.map}, {"op", args.op}, {"out", args.out}};
  if (queryOpReadsPoints(op)) {
    summary.update(runPointQuery(args, op, loaded.map, records));
    summary["points"] = args.points;
  } else if (op == QueryOp::kGrid) {
    summary.update(runGrid(args, loaded.map, loaded.data_up));
  } else {
    summary.update(runOctomap(args, loaded.map));
  }
  Eigen::Vector3d lo, hi;
  loaded.map.seenBounds(&lo, &hi);
  if ((lo.array() <= hi.array()).all())  // where the keyframes see: where grids are laid out
    summary["seen_bounds_m"] = {{rounded6(lo.x()), rounded6(lo.y()), rounded6(lo.z())},
                                {rounded6(hi.x()), rounded6(hi.y()), rounded6(hi.z())}};
  summary["keyframes"] = loaded.keyframes;
  summary["ellipsoids"] = loaded.ellipsoids;
  summary["load_ms"] = rounded6(loaded.load_ms);
  summary["build_ms"] = rounded6(loaded.build_ms);
  summary["threads"] = args.params.threads;
  if (loaded.poses_matched >= 0) summary["keyframe_poses_matched"] = loaded.poses_matched;
  if (args.json) {
    std::cout << jsonText(summary) << "\n";
    return;
  }
  printSummary(op, summary, args.out);
}

}  // namespace

void addQueryCommand(CLI::App& app) {
  auto* verb = app.add_subcommand(
      "query", "Ask a session's map what a planner asks (docs/method.md 13): occupied / free / unknown, distance to "
               "the nearest surface, collision of spheres, ray casts; or export a 2-D occupancy grid (ROS map_server) "
               "or an OctoMap .bt with the keyframes' free space");
  auto args = std::make_shared<QueryArgs>();
  verb->add_option("MAP", args->map, "the map: a session file (.vdmap, vdmap map --save)")->required();
  verb->add_option("--op", args->op,
                   "what to ask: classify, distance, collide, ray (of --points), grid, octomap (exports)")
      ->required()
      ->check(CLI::IsMember({"classify", "distance", "collide", "ray", "grid", "octomap"}));
  verb->add_option(
          "--out", args->out,
          "output file: .txt or .ply (classify, distance, collide, ray), NAME.yaml (grid; NAME.pgm beside it), "
          ".bt (octomap); written atomically")
      ->required();
  verb->add_option("--points", args->points,
                   "the records asked about, .txt columns or .ply vertices: classify/distance x y z; collide x y z r "
                   "[body] (PLY: radius [body]); ray ox oy oz dx dy dz [max_range] (PLY: x y z nx ny nz)");
  verb->add_flag("--json", args->json, "print the summary as JSON");
  verb->add_option("--keyframe", args->keyframe,
                   "classify in keyframe K's local map alone (the paper's arm-planning case)")
      ->check(CLI::NonNegativeNumber);
  verb->add_option("--clearance", args->clearance_m,
                   "collide: a sphere collides closer than its radius + M to a surface")
      ->check(CLI::NonNegativeNumber & finiteCheck())
      ->capture_default_str();
  verb->add_option("--max-range", args->max_range_m, "ray: the range of rays without their own max_range (m)")
      ->check(positiveFiniteCheck())
      ->capture_default_str();
  verb->add_option("--max-distance", args->max_distance_m,
                   "distance: stop looking past M (m); a point farther reads 'at least M' (default: no limit)")
      ->check(positiveFiniteCheck());
  verb->add_option("--gate-sigma", args->params.gate_sigma,
                   "k: occupied within k sigma of an ellipsoid, free more than k sigma in front of a surface")
      ->check(positiveFiniteCheck(QueryParams::kMaxGateSigma))
      ->capture_default_str();
  verb->add_option("--min-sigma", args->params.min_sigma_m,
                   "m, added as min_sigma^2 I to every covariance (a floor for flat ellipsoids)")
      ->check(positiveFiniteCheck(QueryParams::kMaxMinSigmaM))
      ->capture_default_str();
  verb->add_option("--conflict", args->conflict,
                   "a point one keyframe sees free and another occupied: occupied (any global gate wins), recent (the "
                   "keyframe observed last), precise (the most precise view)")
      ->check(CLI::IsMember({"occupied", "recent", "precise"}))
      ->capture_default_str();
  verb->add_option("--keyframe-poses", args->keyframe_poses,
                   "corrected keyframe poses (TUM, matched by timestamp) applied before the map is built; the local "
                   "maps are not integrated again");
  verb->add_option("--resolution", args->resolution_m, "grid cell / OctoMap voxel side (m)")
      ->check(positiveFiniteCheck())
      ->capture_default_str();
  verb->add_option("--band", args->band, "grid: the height band LO:HI (m along --up) a column is read over")
      ->check(parsedBy(parseGridBand, "LO:HI"));
  verb->add_option("--up", args->up,
                   "grid: the axis the band runs along; data: the one nearest the session's estimated up (its "
                   "cameras and floor, as the workbench's)")
      ->check(CLI::IsMember({"+z", "-z", "+y", "-y", "+x", "-x", "data"}))
      ->capture_default_str();
  verb->add_option("--threads", args->params.threads,
                   "threads, 0.." + std::to_string(kMaxThreads) + " (0: all); the answers do not depend on it")
      ->check(CLI::Range(0, kMaxThreads))
      ->capture_default_str();
  verb->callback([args, verb] { runQuery(*args, *verb); });
}

}  // namespace vdmap::app
