#pragma once
// Frame-to-keyframe tracking with a constant-velocity motion model (docs/method.md 8).

#include <optional>
#include <span>

#include "mapping/keyframe/keyframe_graph.h"
#include "mapping/tracking/relative_pose.h"

namespace vdmap {

struct TrackerParams {
  RelativePoseParams relative;
  /// When the current keyframe gives only a weak or no estimate, this many other keyframes
  /// (those the revisit search's pose pre-filter accepts at the predicted pose, most promising
  /// covisibility bound first) are tried; the first good estimate places the frame.
  int relocalisation_candidates = 3;
  /// After lost frames, also up to this many keyframes place recognition proposes
  /// (Tracker::track's `recognised`), whatever the stale prediction says.
  int recognition_candidates = 8;
  /// A weak estimate that PnP does not support (the local map alone: no texture, or a jump the
  /// prediction did not follow) continues the track only when its dense inliers are at least
  /// min_dense_only_share of the frame's points and its surfaces pin the translation
  /// (NdtRefinementResult::translationConditioning() at least min_dense_only_conditioning, the
  /// map registration's bound). Such estimates stay near the stale prediction wherever the
  /// surfaces fit: after the built-in 8-lap walk's jump between laps, a patch of wall (a small
  /// share of the frame's points) placed a frame far from the truth and the lap after it was
  /// mapped there; a textureless box-room frame fitted most of its points at a pose far from the
  /// truth, but its surfaces left the translation free (docs/notes/tracking.md, "Weak frames").
  double min_dense_only_share = 0.5;
  double min_dense_only_conditioning = 0.03;
  /// The current keyframe's estimate takes the photometric term when PnP fails
  /// (RelativePoseParams::photometric). Where the view slides along a plain surface with no PnP
  /// (a white cabinet front, a painted corner), the local map alone cannot see the slide and
  /// carries the frames far from the truth; the image can (docs/notes/tracking.md has the Replica
  /// office0 figures).
  bool photometric = true;
};

/// What the tracker carries from frame to frame (a saved session needs it to continue). The last
/// pose is kept relative to its keyframe, so a pose-graph correction moves the prediction too.
struct TrackerState {
  int keyframe = -1;                           ///< keyframe of the last placed frame (-1: none yet)
  Transform T_K_C = Transform::Identity();     ///< the last placed frame in that keyframe
  Transform velocity = Transform::Identity();  ///< T_Cprev_Ccur of the last two placed frames
  int frames_lost = 0;                         ///< frames skipped since the last placed one
};

/// The outcome for one frame.
struct TrackingOutcome {
  RelativePose estimate;     ///< against `keyframe`
  int keyframe = -1;         ///< the keyframe the pose is relative to (-1: lost)
  bool relocalised = false;  ///< placed against another keyframe than the current one
  bool weak = false;         ///< the current keyframe's estimate was not good
  bool lost() const { return keyframe < 0; }
};

/// Places frames relative to the current keyframe, or relocalises them against nearby ones.
/// Deterministic. Not thread-safe: one thread feeds it.
class Tracker {
 public:
  explicit Tracker(const TrackerParams& params = {}) : params_(params) {}

  /// The constant-velocity prediction of the next frame's pose, world frame; nullopt before
  /// the first placed frame.
  std::optional<Transform> predict(const KeyframeGraph& graph) const;

  /// Estimates the frame's pose against keyframe `current`; when that is not good, against
  /// up to relocalisation_candidates others near the prediction and, after lost frames, up to
  /// recognition_candidates of `recognised` (place recognition's proposals, best first). The
  /// first good one wins; else a weak estimate of the current keyframe is kept unless frames
  /// were lost; else the frame is lost. Does not change the state: call accept() or lose()
  /// with what the caller did with the frame.
  TrackingOutcome track(const KeyframeGraph& graph, int current, const TrackingFrame& frame,
                        const PinholeCamera& camera, const PosePrefilter& prefilter,
                        std::span<const int> recognised = {}) const;
  /// Frames lost since the last placed one.
  int framesLost() const { return state_.frames_lost; }

  /// The frame was placed at T_K_C in keyframe `keyframe` (updates the velocity).
  void accept(const KeyframeGraph& graph, int keyframe, const Transform& T_K_C);
  /// The frame could not be placed: the next prediction has no velocity and a wider motion check.
  void lose() {
    ++state_.frames_lost;
    state_.velocity = Transform::Identity();
  }

  const TrackerState& state() const { return state_; }
  void restore(const TrackerState& state) { state_ = state; }
  const TrackerParams& params() const { return params_; }

 private:
  TrackerParams params_;
  TrackerState state_;
};

}  // namespace vdmap
