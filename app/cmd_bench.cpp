// vdmap bench SEQ: the paper's comparison (SPEC section 8, issue #8) on the same frames in one
// process: vdmap's local-map update and whole pipeline, OctoMap at 0.10/0.05/0.02 m, the NDT-OM
// baseline at 0.10 m and Open3D's TSDF at 0.02/0.01 m (when its plugin is built). Frames are
// decoded once, before any timing; each method runs over all frames in its own pass, so none
// pays for another's cache pollution. Times are the process's CPU time per frame (cpuTimeMs),
// so a busy machine does not skew the ratios; the pipeline's stage split is the Mapper's own
// wall-clock report. Single-threaded throughout (liboctomap on Debian has no
// OpenMP, the integrator is sequential, the Open3D plugin pins OpenMP to one thread).
// With --mesh every method's map is also scored against the reference (SPEC section 8).
// With --poses track the odometry peers (app/odometry_peers.h) estimate the poses of the same
// frames: CPU ms per frame and ATE against the sequence's ground truth of each.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include <nlohmann/json.hpp>
#include <octomap/OcTree.h>

#include "app/bench_long.h"
#include "app/commands.h"
#include "app/eval_report.h"
#include "app/odometry_peers.h"
#include "app/progress.h"
#include "app/timing.h"
#include "app/tsdf_peer.h"
#include "mapping/core/timing.h"
#include "mapping/baseline/ndt_om_baseline.h"
#include "mapping/core/atomic_file.h"
#include "mapping/export/map_export.h"
#include "mapping/global_map/global_map.h"
#include "mapping/io/json_text.h"
#include "mapping/pipeline/mapper.h"
#include "mapping/local_map/local_map_integrator.h"

namespace vdmap::app {
namespace {

struct BenchArgs {
  SequenceArgs sequence;
  int keyframe_every = 10;
  LocalMapParams local_map;
  std::string mesh;
  std::vector<int> accuracy_cell_sizes;
  std::string out = ".";
  bool json = false;
  bool no_octomap = false;
  bool no_open3d = false;
  std::string poses = "gt";
  bool long_run = false;
  LongRunOptions long_options;
  std::size_t completion_samples = AccuracyParams{}.completion_samples;
};

/// One row of the comparison.
struct MethodResult {
  std::string name;   ///< e.g. "OctoMap 0.05 m"
  std::string key;    ///< JSON prefix, e.g. "octomap_005"
  double ms = 0.0;    ///< median update time per frame
  std::size_t elements = 0;
  std::optional<AccuracyReport> accuracy;
  std::string note;   ///< why a peer did not run

  MethodResult(std::string n, std::string k, double t = 0.0, std::string why = "")
      : name(std::move(n)), key(std::move(k)), ms(t), note(std::move(why)) {}
};

// "OctoMap 0.05 m" and "octomap_005" for prefix "OctoMap", key "octomap", 0.05.
MethodResult peerRow(const std::string& name, const std::string& key, double res_m, const std::string& note = "") {
  char n[64], k[64];
  std::snprintf(n, sizeof n, "%s %.2f m", name.c_str(), res_m);
  std::snprintf(k, sizeof k, "%s_%03d", key.c_str(), static_cast<int>(std::lround(res_m * 100)));
  return MethodResult(n, k, 0.0, note);
}

// The points the integrator uses (every pixel with depth in range), in world coordinates.
octomap::Pointcloud worldCloud(const RgbdFrame& frame, const PinholeCamera& cam, const DepthRange& range) {
  const ColoredPointCloud cloud = toPointCloud(frame, cam, range);
  const Eigen::Isometry3f T = frame.T_W_C.cast<float>();
  octomap::Pointcloud out;
  out.reserve(cloud.size());
  for (const Eigen::Vector3f& p : cloud.points) {
    const Eigen::Vector3f w = T * p;
    out.push_back(w.x(), w.y(), w.z());
  }
  return out;
}

std::vector<Eigen::Vector3f> means(const std::vector<Ellipsoid>& ellipsoids) {
  std::vector<Eigen::Vector3f> out;
  out.reserve(ellipsoids.size());
  for (const Ellipsoid& e : ellipsoids) out.push_back(e.mean.cast<float>());
  return out;
}

struct Comparison {
  const std::vector<RgbdFrame>& frames;
  const PinholeCamera& cam;
  const BenchArgs& args;
  const ColoredTriangleMesh* mesh;  // null: no accuracy

  void score(MethodResult* r, const std::vector<Eigen::Vector3f>& points) const {
    r->elements = points.size();
    if (!mesh) return;
    AccuracyParams p;
    p.completion_samples = args.completion_samples;
    r->accuracy = evaluateAccuracy(points, *mesh, p);
  }

  MethodResult octomap(double res) const {
    MethodResult r = peerRow("OctoMap", "octomap", res);
    octomap::OcTree tree(res);
    std::vector<double> ms;
    ProgressBar progress(r.name, frames.size());
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const octomap::Pointcloud cloud = worldCloud(frames[i], cam, args.local_map.depth_range);
      const Eigen::Vector3d c = frames[i].T_W_C.translation();
      ms.push_back(cpuTimeMs([&] { tree.insertPointCloud(cloud, octomap::point3d(c.x(), c.y(), c.z())); }));
      progress.update(i + 1);
    }
    r.ms = median(ms);
    // Elements: occupied voxels at the finest resolution (pruned blocks expanded), centres.
    tree.expand();
    std::vector<Eigen::Vector3f> centres;
    for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it)
      if (tree.isNodeOccupied(*it)) centres.emplace_back(it.getX(), it.getY(), it.getZ());
    score(&r, centres);
    return r;
  }

  MethodResult ndtOm(double res) const {
    MethodResult r = peerRow("NDT-OM baseline", "ndt_om", res);
    NdtOmParams p;
    p.resolution_m = res;
    p.depth_range = args.local_map.depth_range;
    NdtOmBaseline map(p);
    std::vector<double> ms;
    for (const RgbdFrame& f : frames) ms.push_back(cpuTimeMs([&] { map.integrateFrame(f, cam); }));
    r.ms = median(ms);
    score(&r, map.means());
    return r;
  }

  MethodResult tsdf(double voxel) const {
    MethodResult r = peerRow("Open3D TSDF", "open3d_tsdf", voxel);
    // Truncation of 4 voxels, Open3D's examples' ratio (0.04 m at ~0.01 m voxels).
    std::unique_ptr<TsdfVolume> volume =
        TsdfVolume::open(voxel, 4 * voxel, cam, args.local_map.depth_range.max_m, &r.note);
    if (!volume) return r;
    std::vector<double> ms;
    ProgressBar progress(r.name, frames.size());
    for (std::size_t i = 0; i < frames.size(); ++i) {
      ms.push_back(volume->integrate(frames[i]));
      progress.update(i + 1);
    }
    r.ms = median(ms);
    score(&r, volume->extractPoints());
    return r;
  }
};

// A peer that did not run has null figures, as at the top level of bench.json (not 0).
nlohmann::json methodJson(const MethodResult& r) {
  const bool ran = r.note.empty();
  nlohmann::json j = {{"name", r.name},
                      {"ms_per_frame", ran ? nlohmann::json(rounded(r.ms)) : nlohmann::json(nullptr)},
                      {"elements", ran ? nlohmann::json(r.elements) : nlohmann::json(nullptr)}};
  if (r.accuracy) j["accuracy"] = toJson(*r.accuracy);
  if (!r.note.empty()) j["note"] = r.note;
  return j;
}

std::string markdownTable(const std::vector<MethodResult>& rows, double vd_ms, bool accuracy) {
  std::ostringstream md;
  md << "| method | t_u [ms/frame] | x vdmap update | elements |";
  if (accuracy) md << " RMSE [mm] | mean [mm] | median [mm] | completion [mm] | within 5 cm |";
  md << "\n|---|---:|---:|---:|" << (accuracy ? "---:|---:|---:|---:|---:|" : "") << "\n";
  char buf[512];
  for (const MethodResult& r : rows) {
    if (!r.note.empty()) {
      md << "| " << r.name << " | not run: " << r.note << " |\n";
      continue;
    }
    std::snprintf(buf, sizeof buf, "| %s | %.2f | %.1f | %zu |", r.name.c_str(), r.ms, vd_ms > 0 ? r.ms / vd_ms : 0.0,
                  r.elements);
    md << buf;
    if (accuracy && r.accuracy) {
      const AccuracyReport& a = *r.accuracy;
      std::snprintf(buf, sizeof buf, " %.2f | %.2f | %.2f | %.1f | %.1f%% |", a.rmse_mm, a.mean_mm, a.median_mm,
                    a.completion_mean_mm, 100 * a.completion_ratio);
      md << buf;
    } else if (accuracy) {
      md << " | | | | |";
    }
    md << "\n";
  }
  return md.str();
}

struct OdometryRow {
  OdometryRun run;
  double ms = 0.0;  ///< median CPU ms per registered frame
  std::optional<TrajectoryError> error;
};

/// The odometry peers on the decoded frames (--poses track), scored against the frames' ground
/// truth. Each peer's trajectory is written to trajectory_<key>.txt in `out_dir` (TUM).
std::vector<OdometryRow> odometryPeers(const std::vector<RgbdFrame>& frames, const PinholeCamera& cam,
                                       const BenchArgs& args, const std::filesystem::path& out_dir) {
  std::vector<StampedPose> groundtruth;
  for (const RgbdFrame& f : frames) groundtruth.push_back({f.timestamp, f.T_W_C});
  std::vector<OdometryPeerParams> peers;
  for (const OdometryMethod m : {OdometryMethod::kOpenCvRgbd, OdometryMethod::kOpenCvIcp})
    for (const OdometryReference r : {OdometryReference::kPreviousFrame, OdometryReference::kKeyframe})
      peers.push_back({m, r});
  peers.push_back({OdometryMethod::kOpen3dHybrid, OdometryReference::kPreviousFrame});
  std::vector<OdometryRow> rows;
  for (const OdometryPeerParams& p : peers) {
    OdometryRow row;
    if (p.method == OdometryMethod::kOpen3dHybrid && args.no_open3d) {
      row.run = describeOdometryPeer(p);
      row.run.note = "--no-open3d";
    } else {
      ProgressBar progress(describeOdometryPeer(p).name, frames.size());
      row.run = runOdometryPeer(p, frames, cam, [&](std::size_t n) { progress.update(n); });
    }
    if (row.run.note.empty()) {
      row.ms = median(row.run.ms);
      if (frames.size() >= 3) row.error = evaluateTrajectory(row.run.trajectory, groundtruth);
      writeTumTrajectory(out_dir / ("trajectory_" + row.run.key + ".txt"), row.run.trajectory,
                         "vdmap bench: " + row.run.name);
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

/// vdmap's own tracking (PoseSource::kTrack) on the decoded frames as a row of the odometry
/// table: the whole pipeline (features, tracking, keyframe decision, loop closure, local-map
/// update), CPU ms per frame, scored like the peers; its trajectory goes to
/// trajectory_<key>.txt. Without loop closure it shows what the pose graph adds. `refinement` (may
/// be null) receives the map refinement after the last frame (--refine), run only when it is given.
OdometryRow trackVdmap(const std::vector<RgbdFrame>& frames, const PinholeCamera& cam, const BenchArgs& args,
                       bool loops, const std::filesystem::path& out_dir, int* loop_closures,
                       MapRefinementResult* refinement) {
  MapperParams params;
  params.local_map = args.local_map;
  params.poses = PoseSource::kTrack;
  TrackingParams tracking;
  tracking.loops.enabled = loops;
  Mapper mapper(cam, params, tracking);
  OdometryRow row;
  row.run.name = loops ? "vdmap tracking + loop closure (whole pipeline)" : "vdmap tracking, no loop closure (whole pipeline)";
  row.run.key = loops ? "vdmap_track" : "vdmap_track_no_loops";
  ProgressBar progress(row.run.name, frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) {
    row.run.ms.push_back(cpuTimeMs([&] { mapper.addFrame(frames[i]); }));
    progress.update(i + 1);
  }
  // With `refinement` (the loop-closure row), the whole pipeline ends as `vdmap map` does: keyframe
  // poses refined from the settled local maps (once, not per frame: its time is reported beside the table).
  if (refinement)
    if (const std::optional<MapRefinementParams> refine = app::refinement(args.sequence))
      *refinement = mapper.refineKeyframePoses(*refine);
  row.run.trajectory = mapper.trajectory();
  row.run.failures = mapper.framesLost();
  row.run.keyframes = static_cast<int>(mapper.graph().size());
  *loop_closures = static_cast<int>(mapper.poseGraph().loops().size());
  row.ms = median(row.run.ms);
  std::vector<StampedPose> groundtruth;
  for (const RgbdFrame& f : frames) groundtruth.push_back({f.timestamp, f.T_W_C});
  if (row.run.trajectory.size() >= 3) row.error = evaluateTrajectory(row.run.trajectory, groundtruth);
  writeTumTrajectory(out_dir / ("trajectory_" + row.run.key + ".txt"), row.run.trajectory, "vdmap bench: " + row.run.name);
  return row;
}

nlohmann::json odometryJson(const OdometryRow& r, std::size_t frames) {
  nlohmann::json j = {{"name", r.run.name}, {"frames", frames}};
  if (!r.run.note.empty()) {
    j["note"] = r.run.note;
    return j;
  }
  j["ms_per_frame"] = rounded(r.ms);
  j["failures"] = r.run.failures;
  if (r.run.keyframes > 0) j["keyframes"] = r.run.keyframes;
  j["ate_rmse_m"] = r.error ? nlohmann::json(rounded(r.error->ate_m.rmse)) : nlohmann::json(nullptr);
  if (r.error) j["rpe_per_frame"] = toJson(r.error->rpe_per_frame);
  return j;
}

std::string odometryTable(const std::vector<OdometryRow>& rows) {
  std::ostringstream md;
  md << "| method | t [ms/frame] | ATE RMSE [cm] | frames not registered | keyframes |\n|---|---:|---:|---:|---:|\n";
  for (const OdometryRow& r : rows) {
    if (!r.run.note.empty()) {
      md << "| " << r.run.name << " | not run: " << r.run.note << " |\n";
      continue;
    }
    char buf[256], ate[32] = "-", keyframes[32] = "-";  // per row: a row without them shows "-"
    if (r.error) std::snprintf(ate, sizeof ate, "%.2f", 100 * r.error->ate_m.rmse);
    if (r.run.keyframes > 0) std::snprintf(keyframes, sizeof keyframes, "%d", r.run.keyframes);
    std::snprintf(buf, sizeof buf, "| %s | %.2f | %s | %d | %s |\n", r.run.name.c_str(), r.ms, ate, r.run.failures,
                  keyframes);
    md << buf;
  }
  return md.str();
}

// The pipeline's CPU per frame (medians): all of it on one thread, the mapping thread's share
// (latency once the features are ready) and the frame rate with decoding and ORB on the
// prefetch thread (bound by the slower of the two threads).
std::string pipelineLine(double total_ms, double features_ms, double mapping_ms, double decode_ms, double fps) {
  char line[320];
  std::snprintf(line, sizeof line,
                "Pipeline CPU per frame (median): %.2f ms on one thread (ORB %.2f + decision and update %.2f); with "
                "decoding (%.2f) and ORB on the prefetch thread: latency %.2f ms, throughput %.0f frames/s.",
                total_ms, features_ms, mapping_ms, decode_ms, mapping_ms, fps);
  return line;
}

void runBench(BenchArgs args) {
  if (args.long_run) {  // every frame unless --frames says otherwise, never all decoded at once
    const std::filesystem::path out_dir = args.out;
    checkExportFolder(out_dir);
    MapperParams mapper;
    mapper.local_map = args.local_map;
    mapper.poses = args.poses == "track" ? PoseSource::kTrack : PoseSource::kGroundTruth;
    args.long_options.json = args.json;
    return runLongBench(openSequence(args.sequence), mapper, {}, out_dir, args.long_options, refinement(args.sequence));
  }
  // Frames are held decoded, so the default is a short range: 0:30, or the whole sequence when
  // it is shorter (a range typed past the end is an error, as everywhere).
  const bool default_range = args.sequence.frames.empty();
  if (default_range) args.sequence.frames = "0:30";
  if (args.keyframe_every < 1) throw std::invalid_argument("--keyframe-every must be at least 1");
  // Like map --out: created if missing (checked now, before any work).
  const std::filesystem::path out_dir = args.out;
  checkExportFolder(out_dir);
  std::optional<ColoredTriangleMesh> mesh;
  if (!args.mesh.empty()) mesh = readPlyMesh(args.mesh);  // fail before any work on a bad mesh
  const TumSequence seq = openSequence(args.sequence, default_range);
  const std::string frame_range = frameRangeText(seq.frameRange());
  const PinholeCamera& cam = seq.camera();
  for (const int s : args.accuracy_cell_sizes)
    if (s < 1 || s > std::min(cam.width, cam.height)) throw std::invalid_argument("--accuracy-cell-sizes: bad cell size " + std::to_string(s));

  // Decoded on this thread, each frame timed: decoding is the prefetch thread's share of the
  // pipeline's throughput below.
  std::vector<RgbdFrame> decoded;
  std::vector<double> decode_ms;
  {
    ProgressBar progress("decoding", seq.size());
    for (std::size_t i = 0; i < seq.size(); ++i) {
      decode_ms.push_back(cpuTimeMs([&] { decoded.push_back(seq.load(i)); }));
      progress.update(decoded.size());
    }
  }
  const Comparison cmp{decoded, cam, args, mesh ? &*mesh : nullptr};

  // vdmap: every frame into the current keyframe; a new keyframe every N frames (its empty
  // container is made outside the timed region, as a keyframe's creation is not an update).
  std::vector<double> vd_ms;
  std::size_t cells = 0, bytes = 0;
  {
    LocalMapIntegrator integrator(args.local_map);
    std::unique_ptr<KeyframeContainer> container;
    Transform T_W_K;
    std::vector<int> touched;
    for (std::size_t i = 0; i < decoded.size(); ++i) {
      if (i % args.keyframe_every == 0) {
        if (container) cells += container->size(), bytes += container->memoryBytes();
        container = std::make_unique<KeyframeContainer>(cam, args.local_map.cell_size_px);
        T_W_K = decoded[i].T_W_C;
      }
      vd_ms.push_back(cpuTimeMs([&] {
        integrator.integrateFrame(decoded[i], cam, T_W_K, container.get(), &touched);
      }));
    }
    if (container) cells += container->size(), bytes += container->memoryBytes();
  }

  // The whole per-frame path (features, keyframe decision, update) on the same frames, then
  // the global map of the keyframes it made: its ellipsoid means are vdmap's map elements.
  // Features are computed as the prefetch thread does (Mapper::featuresAhead) and timed apart
  // from the mapping thread's share (decision and update): the pipeline's CPU per frame is
  // their sum, its latency the mapping share, its throughput bound by the slower thread.
  std::vector<double> pipeline_ms, features_cpu_ms, mapping_cpu_ms, decision_ms, update_ms;
  MapperParams mapper_params;
  mapper_params.local_map = args.local_map;
  Mapper mapper(cam, mapper_params);
  {
    ProgressBar progress("pipeline", decoded.size());
    const auto features_ahead = mapper.featuresAhead();
    for (RgbdFrame frame : decoded) {  // a copy: the features stay out of `decoded`
      FrameReport r;
      features_cpu_ms.push_back(cpuTimeMs([&] { features_ahead(frame); }));
      mapping_cpu_ms.push_back(cpuTimeMs([&] { r = mapper.addFrame(frame); }));
      pipeline_ms.push_back(features_cpu_ms.back() + mapping_cpu_ms.back());
      decision_ms.push_back(r.ms.decision_ms);
      update_ms.push_back(r.ms.update_ms);
      progress.update(pipeline_ms.size());
    }
  }
  const double mapping_ms = median(mapping_cpu_ms);
  const double fps = 1e3 / std::max({median(decode_ms) + median(features_cpu_ms), mapping_ms, 1e-9});
  const std::string pipeline_line =
      pipelineLine(median(pipeline_ms), median(features_cpu_ms), mapping_ms, median(decode_ms), fps);
  const GlobalMap global = buildGlobalMap(mapper.graph(), {});
  const double vd = median(vd_ms);

  std::vector<MethodResult> rows;
  rows.emplace_back("vdmap update " + std::to_string(args.local_map.cell_size_px) + " px", "vd_update", vd);
  cmp.score(&rows.back(), means(global.ellipsoids));
  rows.emplace_back("vdmap pipeline", "vd_pipeline", median(pipeline_ms));
  rows.back().elements = global.ellipsoids.size();
  rows.back().accuracy = rows[rows.size() - 2].accuracy;
  // Accuracy at other cell sizes: the whole pipeline again (untimed) with that cell size.
  for (const int s : args.accuracy_cell_sizes) {
    if (s == args.local_map.cell_size_px) continue;
    MapperParams p = mapper_params;
    p.local_map.cell_size_px = s;
    Mapper m(cam, p);
    ProgressBar progress("vdmap " + std::to_string(s) + " px", decoded.size());
    for (std::size_t i = 0; i < decoded.size(); ++i) {
      m.addFrame(decoded[i]);
      progress.update(i + 1);
    }
    const GlobalMap g = buildGlobalMap(m.graph(), {});
    rows.emplace_back("vdmap " + std::to_string(s) + " px (accuracy only)", "vd_" + std::to_string(s) + "px");
    cmp.score(&rows.back(), means(g.ellipsoids));
  }
  const std::size_t first_peer = rows.size();
  for (const double res : {0.10, 0.05, 0.02})
    rows.push_back(args.no_octomap ? peerRow("OctoMap", "octomap", res, "--no-octomap") : cmp.octomap(res));
  rows.push_back(cmp.ndtOm(0.10));
  for (const double voxel : {0.02, 0.01})
    rows.push_back(args.no_open3d ? peerRow("Open3D TSDF", "open3d_tsdf", voxel, "--no-open3d") : cmp.tsdf(voxel));

  std::vector<OdometryRow> odometry;
  int loop_closures = 0, no_loops = 0;
  MapRefinementResult refinement;
  if (args.poses == "track") {
    std::filesystem::create_directories(out_dir);  // the trajectories go there
    odometry.push_back(trackVdmap(decoded, cam, args, true, out_dir, &loop_closures, &refinement));
    odometry.push_back(trackVdmap(decoded, cam, args, false, out_dir, &no_loops, nullptr));
    for (OdometryRow& row : odometryPeers(decoded, cam, args, out_dir)) odometry.push_back(std::move(row));
  }

  const auto ratio = [vd](double o) { return vd > 0 ? o / vd : 0.0; };
  nlohmann::json out = {
      {"frames", decoded.size()},
      {"frame_range", frame_range},
      {"vd_update_ms", rounded(vd)},
      {"vd_update_ms_max", rounded(vd_ms.empty() ? 0.0 : *std::max_element(vd_ms.begin(), vd_ms.end()))},
      {"cell_size_px", args.local_map.cell_size_px},
      {"keyframe_every", args.keyframe_every},
      {"ellipsoids", cells},
      {"bytes_per_ellipsoid", sizeof(StoredCell)},
      {"container_bytes", bytes},
      {"vd_pipeline_ms", rounded(median(pipeline_ms))},
      {"pipeline_stage_ms", {{"features", rounded(median(features_cpu_ms))}, {"decision", rounded(median(decision_ms))},
                             {"update", rounded(median(update_ms))}, {"decode", rounded(median(decode_ms))}}},
      {"vd_pipeline_latency_ms", rounded(mapping_ms)},
      {"vd_pipeline_fps", rounded(fps)},
      {"revisits", mapper.revisits()},
  };
  out.update(globalMapStats(mapper.graph(), global));  // keyframes, sigma_e, sigma_e', t_g, ...
  const double t_g_us = out["t_g_us_per_ellipsoid"];
  for (std::size_t i = first_peer; i < rows.size(); ++i) {
    const MethodResult& r = rows[i];
    out[r.key + "_ms"] = r.note.empty() ? nlohmann::json(rounded(r.ms)) : nlohmann::json(nullptr);
    out["ratio_" + r.key] = r.note.empty() ? nlohmann::json(rounded(ratio(r.ms))) : nlohmann::json(nullptr);
  }
  out["ratio_octomap_010_pipeline"] = median(pipeline_ms) > 0 && rows[first_peer].note.empty()
                                          ? nlohmann::json(rounded(rows[first_peer].ms / median(pipeline_ms)))
                                          : nlohmann::json(nullptr);
  out["methods"] = nlohmann::json::object();  // sorted by key, so the table's order goes beside it
  out["method_order"] = nlohmann::json::array();
  for (const MethodResult& r : rows) {
    out["methods"][r.key] = methodJson(r);
    out["method_order"].push_back(r.key);
  }
  if (mesh) out["mesh"] = args.mesh;
  out["poses"] = args.poses;
  if (!odometry.empty()) {
    out["odometry"] = nlohmann::json::object();
    out["odometry_order"] = nlohmann::json::array();
    for (const OdometryRow& r : odometry) {
      out["odometry"][r.run.key] = odometryJson(r, decoded.size());
      out["odometry_order"].push_back(r.run.key);
    }
    // What tracking adds to the pipeline: the tracked pipeline's median CPU time per frame
    // minus the ground-truth pipeline's, on the same frames.
    out["vd_tracking_added_ms"] = odometry.front().ms - median(pipeline_ms);
    out["odometry"]["vdmap_track"]["loop_closures"] = loop_closures;
    out["odometry"]["vdmap_track"]["map_refinement"] = args.sequence.refine;
    out["odometry"]["vdmap_track"]["map_refinement_ms"] = rounded(refinement.ms);
  }

  std::ostringstream md;
  char global_line[256];
  std::snprintf(global_line, sizeof global_line,
                "Global map: %s, Sigma_e %zu -> Sigma_e' %zu in %.3f s (%.2f us per ellipsoid).\n",
                counted(mapper.graph().size(), "keyframe").c_str(), global.sigma_e, global.sigma_e_prime, global.t_g_s,
                t_g_us);
  md << "# vdmap bench\n\n" << decoded.size() << " frames of `" << args.sequence.folder << "` (" << cam.width << "x"
     << cam.height << "), frames " << frame_range << ", keyframe every " << args.keyframe_every
     << " (update) / covisibility (pipeline), one thread. Times are medians of CPU time per frame.\n\n"
     << markdownTable(rows, vd, mesh.has_value()) << "\n" << pipeline_line << "\n\n" << global_line;
  if (!odometry.empty())
    md << "\nTracking (--poses track) on the same frames, one thread: median CPU time per frame (vdmap: its whole "
          "pipeline, which tracking makes " << out["vd_tracking_added_ms"].get<double>() << " ms slower than with "
          "ground-truth poses; the peers: registration only), ATE after the rigid alignment against the sequence's "
          "ground truth. vdmap closed " << loop_closures << " loops; with loop closure its keyframe poses are "
          "refined from the local maps after the last frame (--refine " << args.sequence.refine << ", "
       << rounded(refinement.ms) << " ms, not in the per-frame time).\n\n"
       << odometryTable(odometry);
  std::filesystem::create_directories(out_dir);
  writeFileAtomically(out_dir / "bench.json", jsonText(out) + "\n");
  writeFileAtomically(out_dir / "bench.md", md.str());
  if (args.json) {
    std::cout << jsonText(out) << "\n";
    return;
  }
  std::printf("frames          %zu of %s (%dx%d), keyframe every %d, cell %d px\n", decoded.size(),
              frame_range.c_str(), cam.width, cam.height, args.keyframe_every, args.local_map.cell_size_px);
  std::printf("%s\n", pipeline_line.c_str());
  std::printf("Wall-clock stages on the mapping thread: decision %.2f, update %.2f ms\n", median(decision_ms),
              median(update_ms));
  std::printf("global map      %s, Sigma_e %zu -> Sigma_e' %zu in %.3f s (%.2f us per ellipsoid)\n",
              counted(mapper.graph().size(), "keyframe").c_str(), global.sigma_e, global.sigma_e_prime, global.t_g_s, t_g_us);
  std::printf("\n%-34s %12s %10s %10s\n", "method", "ms/frame", "x vdmap", "elements");
  for (const MethodResult& r : rows) {
    if (!r.note.empty()) {
      std::printf("%-34s not run: %s\n", r.name.c_str(), r.note.c_str());
      continue;
    }
    std::printf("%-34s %12.2f %10.1f %10zu\n", r.name.c_str(), r.ms, ratio(r.ms), r.elements);
    if (r.accuracy) std::printf("    %s\n", toText(*r.accuracy).c_str());
  }
  if (!odometry.empty())
    std::printf("\n%-48s %12s %10s %10s %10s\n", "tracking (vdmap: whole pipeline)", "ms/frame", "ATE [cm]", "lost", "keyframes");
  for (const OdometryRow& r : odometry) {
    if (!r.run.note.empty()) {
      std::printf("%-44s not run: %s\n", r.run.name.c_str(), r.run.note.c_str());
      continue;
    }
    char ate[32] = "-";
    if (r.error) std::snprintf(ate, sizeof ate, "%.2f", 100 * r.error->ate_m.rmse);
    std::printf("%-48s %12.2f %10s %10d %10s\n", r.run.name.c_str(), r.ms, ate, r.run.failures,
                r.run.keyframes > 0 ? std::to_string(r.run.keyframes).c_str() : "-");
  }
  if (!odometry.empty())
    std::printf("tracking adds %.2f ms per frame to vdmap's pipeline (CPU medians); %d loop closures; keyframe poses "
                "refined from the local maps after the last frame (--refine %s) in %.0f ms (wall)\n",
                out["vd_tracking_added_ms"].get<double>(), loop_closures, args.sequence.refine.c_str(), refinement.ms);
  std::printf("\nwrote %s and %s\n", (out_dir / "bench.json").c_str(), (out_dir / "bench.md").c_str());
}

}  // namespace

void addBenchCommand(CLI::App& app) {
  auto* verb = app.add_subcommand("bench", "Compare vdmap with OctoMap, NDT-OM and Open3D's TSDF on the same frames");
  auto args = std::make_shared<BenchArgs>();
  addSequenceArgs(*verb, args->sequence);
  verb->get_option("--frames")->description(
      "frames A:B of the depth list; a plain N means 0:N (default 0:30, or fewer when the sequence is "
      "shorter); a range past the end is an error. Frames are held decoded in memory, ~1.5 MB each at 640x480");
  verb->add_option("--keyframe-every", args->keyframe_every, "every N-th frame starts a keyframe (update timing)")
      ->capture_default_str();
  verb->add_option("--cell-size", args->local_map.cell_size_px, "container cell size, px")->capture_default_str();
  verb->add_option("--mesh", args->mesh, "reference mesh PLY (world frame of the poses): adds every method's accuracy")
      ->check(CLI::ExistingFile);
  verb->add_option("--accuracy-cell-sizes", args->accuracy_cell_sizes,
                   "with --mesh, also score vdmap at these cell sizes, px (e.g. 3,5,9,15)")
      ->delimiter(',');
  verb->add_option("--samples", args->completion_samples, "mesh samples for completion")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{1}, AccuracyParams::kMaxCompletionSamples));
  verb->add_option("--out", args->out, "folder for bench.json and bench.md")->capture_default_str();
  verb->add_flag("--no-octomap", args->no_octomap, "skip the OctoMap peers (for profiling)");
  verb->add_flag("--no-open3d", args->no_open3d, "skip the Open3D peers (TSDF, and odometry with --poses track)");
  verb->add_option("--poses", args->poses,
                   "gt: map with the sequence's ground-truth poses; track: also track the poses with vdmap (with and "
                   "without loop closure) and the odometry peers (OpenCV RgbdOdometry and ICPOdometry frame to frame "
                   "and against keyframes, Open3D's hybrid odometry) on the same frames: ms per frame and ATE "
                   "against the ground truth, and trajectory_<method>.txt in --out")
      ->capture_default_str()
      ->check(CLI::IsMember({"gt", "track"}));
  addRefineArg(*verb, args->sequence);
  verb->add_flag("--long", args->long_run,
                 "the long run instead (issue 16): every frame (or --frames) mapped as `vdmap map` does, the mapping "
                 "thread's CPU time per frame, resident memory, live heap, keyframes and the global map's size into "
                 "long.csv and long.json; with --poses track the poses are tracked (and refined as --refine says) "
                 "and long.json adds frames lost, loop closures and the ATE");
  verb->add_option("--global-every", args->long_options.global_every, "with --long: frames between global-map builds")
      ->capture_default_str();
  verb->add_flag("--json", args->json, "print JSON instead of text");
  verb->callback([args] { runBench(*args); });
}

}  // namespace vdmap::app
