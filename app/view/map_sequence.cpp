#include "app/view/map_sequence.h"

#include <nlohmann/json.hpp>

#include "app/view/progress.h"
#include "mapping/core/timing.h"
#include "mapping/eval/trajectory_error.h"
#include "mapping/sequence/frame_prefetcher.h"

namespace vdmap::app {

MapRefinementResult mapSequence(const Sequence& seq, Mapper& mapper,
                                const std::function<void(const FrameReport&)>& on_frame,
                                const std::optional<MapRefinementParams>& refine) {
  FramePrefetcher frames(seq, 4, mapper.featuresAhead());
  ProgressBar progress("mapping", seq.size());
  std::size_t done = 0;  // of this sequence (a continued session has mapped others before)
  while (std::optional<RgbdFrame> frame = frames.next()) {
    const FrameReport report = mapper.addFrame(*frame);
    if (on_frame) on_frame(report);
    progress.update(++done);
  }
  return refine && mapper.params().poses == PoseSource::kTrack ? mapper.refineKeyframePoses(*refine)
                                                               : MapRefinementResult{};
}

std::vector<StampedPose> groundTruthTrajectory(const Sequence& seq) {
  std::vector<StampedPose> out;
  for (const FrameEntry& e : seq.entries())
    if (e.has_pose) out.push_back({e.t_depth, e.T_W_C});
  return out;
}

void addTrackingStats(const Mapper& mapper, const std::vector<StampedPose>& trajectory, const Sequence& seq,
                      nlohmann::json* stats) {
  nlohmann::json& s = *stats;
  s["frames_lost"] = mapper.framesLost();
  s["frames_weak"] = mapper.framesWeak();
  s["frames_relocalised"] = mapper.framesRelocalised();
  double pose_graph_ms = 0;
  for (const LoopClosure& loop : mapper.poseGraph().loops()) pose_graph_ms += loop.pose_graph_ms;
  s["loop_closures"] = mapper.poseGraph().loops().size();
  s["pose_graph_ms"] = rounded(pose_graph_ms);
  const std::vector<StampedPose> groundtruth = groundTruthTrajectory(seq);
  if (groundtruth.size() >= 3 && trajectory.size() >= 3)
    s["ate_rmse_m"] = rounded(evaluateTrajectory(trajectory, groundtruth).ate_m.rmse);
}

}  // namespace vdmap::app
