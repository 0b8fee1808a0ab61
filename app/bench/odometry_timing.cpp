#include "app/bench/odometry_timing.h"

#include "app/view/progress.h"
#include "mapping/core/timing.h"
#include "mapping/io/trajectory_io.h"
#include "mapping/pipeline/mapper.h"

namespace vdmap::app {
namespace {

std::vector<StampedPose> groundTruth(const std::vector<RgbdFrame>& frames) {
  std::vector<StampedPose> groundtruth;
  for (const RgbdFrame& f : frames) groundtruth.push_back({f.timestamp, f.T_W_C});
  return groundtruth;
}

// The row's median, its error against the ground truth (with three poses or more; a peer that
// ran has one per frame) and its trajectory in trajectory_<key>.txt.
void finishRow(const std::vector<RgbdFrame>& frames, const std::filesystem::path& out_dir, OdometryRow* row) {
  row->ms = median(row->run.ms);
  if (row->run.trajectory.size() >= 3) row->error = evaluateTrajectory(row->run.trajectory, groundTruth(frames));
  writeTumTrajectory(out_dir / ("trajectory_" + row->run.key + ".txt"), row->run.trajectory,
                     "vdmap bench: " + row->run.name);
}

/// The odometry peers on the frames, scored against the frames' ground truth.
std::vector<OdometryRow> odometryPeers(const BenchInput& in, const std::filesystem::path& out_dir) {
  std::vector<OdometryPeerParams> peers;
  for (const OdometryMethod m : {OdometryMethod::kOpenCvRgbd, OdometryMethod::kOpenCvIcp})
    for (const OdometryReference r : {OdometryReference::kPreviousFrame, OdometryReference::kKeyframe})
      peers.push_back({m, r});
  peers.push_back({OdometryMethod::kOpen3dHybrid, OdometryReference::kPreviousFrame});
  std::vector<OdometryRow> rows;
  for (const OdometryPeerParams& p : peers) {
    OdometryRow row;
    if (p.method == OdometryMethod::kOpen3dHybrid && in.args.no_open3d) {
      row.run = describeOdometryPeer(p);
      row.run.note = "--no-open3d";
    } else {
      ProgressBar progress(describeOdometryPeer(p).name, in.frames.size());
      row.run = runOdometryPeer(p, in.frames, in.cam, [&](std::size_t n) { progress.update(n); });
    }
    if (row.run.note.empty()) finishRow(in.frames, out_dir, &row);
    rows.push_back(std::move(row));
  }
  return rows;
}

/// vdmap's own tracking (PoseSource::kTrack) on the frames as a row of the odometry table: the
/// whole pipeline (features, tracking, keyframe decision, loop closure, local-map update), CPU ms
/// per frame, scored like the peers. Without loop closure it shows what the pose graph adds.
/// `refinement` (may be null) receives the map refinement after the last frame (--refine), run
/// only when it is given.
OdometryRow trackVdmap(const BenchInput& in, bool loops, const std::filesystem::path& out_dir, int* loop_closures,
                       MapRefinementResult* refinement) {
  MapperParams params;
  params.local_map = in.args.local_map;
  params.poses = PoseSource::kTrack;
  TrackingParams tracking;
  tracking.loops.enabled = loops;
  Mapper mapper(in.cam, params, tracking);
  OdometryRow row;
  row.run.name =
      loops ? "vdmap tracking + loop closure (whole pipeline)" : "vdmap tracking, no loop closure (whole pipeline)";
  row.run.key = loops ? "vdmap_track" : "vdmap_track_no_loops";
  ProgressBar progress(row.run.name, in.frames.size());
  for (std::size_t i = 0; i < in.frames.size(); ++i) {
    row.run.ms.push_back(cpuTimeMs([&] { mapper.addFrame(in.frames[i]); }));
    progress.update(i + 1);
  }
  // With `refinement` (the loop-closure row), the whole pipeline ends as `vdmap map` does: keyframe
  // poses refined from the settled local maps (once, not per frame: its time is reported beside the table).
  if (refinement)
    if (const std::optional<MapRefinementParams> refine = app::refinement(in.args.sequence))
      *refinement = mapper.refineKeyframePoses(*refine);
  row.run.trajectory = mapper.trajectory();
  row.run.failures = mapper.framesLost();
  row.run.keyframes = static_cast<int>(mapper.graph().size());
  *loop_closures = static_cast<int>(mapper.poseGraph().loops().size());
  finishRow(in.frames, out_dir, &row);
  return row;
}

}  // namespace

TrackingRows timeTracking(const BenchInput& in, const std::filesystem::path& out_dir) {
  std::filesystem::create_directories(out_dir);  // the trajectories go there
  TrackingRows t;
  int no_loops = 0;
  t.rows.push_back(trackVdmap(in, true, out_dir, &t.loop_closures, &t.refinement));
  t.rows.push_back(trackVdmap(in, false, out_dir, &no_loops, nullptr));
  for (OdometryRow& row : odometryPeers(in, out_dir)) t.rows.push_back(std::move(row));
  return t;
}

}  // namespace vdmap::app
