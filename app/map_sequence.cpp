#include "app/map_sequence.h"

#include "app/progress.h"
#include "mapping/io/frame_prefetcher.h"

namespace vdmap::app {

MapRefinementResult mapSequence(const TumSequence& seq, Mapper& mapper,
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
  return refine && mapper.params().poses == PoseSource::kTrack ? mapper.refineKeyframePoses(*refine) : MapRefinementResult{};
}

std::vector<StampedPose> groundTruthTrajectory(const TumSequence& seq) {
  std::vector<StampedPose> out;
  for (const FrameEntry& e : seq.entries())
    if (e.has_pose) out.push_back({e.t_depth, e.T_W_C});
  return out;
}

}  // namespace vdmap::app
