#pragma once
#include <span>
#include <utility>
#include <vector>

#include "mapping/keyframe/covisibility.h"

namespace vdmap {

/// docs/method.md 5 thresholds of the per-frame keyframe decision.
struct KeyframeParams {
  double tau = 0.25;        ///< update the current keyframe when delta(F, K_current) >= tau
  double tau_edge = 0.1;    ///< a new keyframe gets an edge to K when delta >= tau_edge
  PosePrefilter prefilter;  ///< skips far / turned-away keyframes in the searches
  /// A frame with fewer keypoints (a textureless view) cannot be judged by covisibility: it
  /// updates the current keyframe when the pose pre-filter accepts that keyframe, else starts a
  /// new one. This keeps blank walls from spawning a keyframe per frame.
  int min_frame_features = 20;
  CovisibilityParams covisibility;
};

/// What the decision needs of one keyframe (non-owning).
struct KeyframeView {
  int id = -1;
  const Transform* T_W_K = nullptr;
  const FrameFeatures* features = nullptr;
};

/// The outcome of the per-frame decision, with the search's cost.
struct FrameDecision {
  enum class Kind { kUpdate, kRevisit, kNewKeyframe };
  Kind kind = Kind::kNewKeyframe;
  int keyframe = -1;         ///< the keyframe to update (kUpdate, kRevisit)
  double delta_current = 0;  ///< delta(F, K_current)
  double delta_best = 0;     ///< best delta of the loop-closure search (0 when not searched)
  int matched = 0;           ///< keyframes matched descriptor by descriptor
  int pruned = 0;            ///< keyframes skipped by the pre-filter or the covisibility bound
};

/// Decides what frame F does (docs/method.md 5): update `current` when delta >= tau; otherwise
/// the keyframe with the best delta >= tau becomes current (a revisit, ties to the lower id);
/// otherwise F starts a new keyframe. `current` < 0 means there is none yet. The loop-closure
/// search prunes with covisibilityBound(), which never changes the result. `keyframes` are the
/// ones considered: all of them (the exhaustive search) or a KeyframeIndex's candidates plus
/// `current`. `measure` is delta (the brute-force oracle in tests).
FrameDecision decideKeyframe(const FrameFeatures& frame, const Transform& T_W_F, int current,
                             std::span<const KeyframeView> keyframes, const PinholeCamera& camera,
                             const KeyframeParams& params, CovisibilityMeasure measure = covisibility);

/// Edges of a newly created keyframe N to the existing `keyframes` (docs/method.md 5): weight
/// delta(N, K) where it is >= tau_edge, plus the edge to `previous` (if >= 0) whatever its
/// weight. Sorted by keyframe id.
std::vector<std::pair<int, double>> edgesOfNewKeyframe(const FrameFeatures& features, const Transform& T_W_N,
                                                       int previous, std::span<const KeyframeView> keyframes,
                                                       const PinholeCamera& camera, const KeyframeParams& params,
                                                       CovisibilityMeasure measure = covisibility);

}  // namespace vdmap
