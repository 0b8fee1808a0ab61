#pragma once
// The mapping loop of the verbs that map a whole sequence (vdmap map, vdmap render SEQ).
#include <functional>
#include <optional>

#include <nlohmann/json_fwd.hpp>

#include "mapping/pipeline/mapper.h"
#include "mapping/sequence/sequence.h"

namespace vdmap::app {

/// Feeds every frame of `seq` to `mapper` in order, decoding the next frame while one is mapped,
/// with a progress bar on stderr; `on_frame`, when given, sees each frame's report. With tracked
/// poses and `refine`, the keyframe poses are then refined from the settled local maps
/// (Mapper::refineKeyframePoses), whose outcome is returned.
MapRefinementResult mapSequence(const Sequence& seq, Mapper& mapper,
                                const std::function<void(const FrameReport&)>& on_frame = {},
                                const std::optional<MapRefinementParams>& refine = MapRefinementParams{});

/// The ground-truth poses of the sequence's frames (those that have one), for trajectory error.
std::vector<StampedPose> groundTruthTrajectory(const Sequence& seq);

/// A tracked run's figures in `stats` (stats.json, long.json): frames_lost, frames_weak,
/// frames_relocalised, loop_closures, pose_graph_ms (all optimisations, wall) and, when `seq` has
/// ground truth, ate_rmse_m of `trajectory` (the mapper's).
void addTrackingStats(const Mapper& mapper, const std::vector<StampedPose>& trajectory, const Sequence& seq,
                      nlohmann::json* stats);

}  // namespace vdmap::app
