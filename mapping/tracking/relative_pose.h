#pragma once
// The pose of a frame relative to one keyframe (docs/method.md 8): PnP RANSAC on the frame's ORB
// matches to the keyframe's keypoints (which have depth), checked against a prediction, then
// refined densely against the keyframe's own local map. Tracking, relocalisation, loop closure
// and the pose-graph edges of new keyframes all measure relative poses with this one function.

#include <functional>
#include <optional>

#include "mapping/keyframe/keyframe_graph.h"
#include "mapping/tracking/ndt_refinement.h"

namespace vdmap {

struct PnpParams {
  int max_hamming = 64;     ///< descriptor distance limit (docs/method.md 5)
  double lowe_ratio = 0.8;  ///< best / second-best distance must be below this
  int min_matches = 12;     ///< fewer matches with depth: no PnP
  int ransac_iterations = 100;
  double ransac_reprojection_px = 3.0;
  int min_inliers = 20;  ///< fewer RANSAC inliers: the PnP pose is not used
  /// With a prior, the keyframe's keypoints are matched by projection (matchByProjection) at
  /// the prior within this radius, and PnP refines the prior on those matches without RANSAC;
  /// when that explains fewer than min_inliers, the brute-force 2-NN matches and RANSAC decide.
  /// 0: always brute force (loop closures, where drift puts the prior far off).
  double search_radius_px = 24.0;
};

/// What the frame needs for a relative-pose estimate (non-owning).
struct TrackingFrame {
  const FrameFeatures* features = nullptr;
  const DensePoints* points = nullptr;
  /// The frame's photometric points, made on first call (only a frame PnP cannot place needs
  /// them); empty: no photometric term.
  std::function<const PhotometricPoints&()> photometric;
};

struct RelativePoseParams {
  PnpParams pnp;
  NdtRefinementParams dense;
  bool dense_refinement = true;  ///< false: PnP alone (for comparison; the tests show it is worse)
  /// Without PnP the local map alone places the frame, free to slide where its surfaces are (two
  /// walls, one flat front): the frame's photometric term against the keyframe's image
  /// (NdtRefinementParams) then joins the refinement. Not with PnP: on 7-Scenes, whose colour and
  /// depth come from two unsynchronised cameras, the term on every frame raised the per-frame
  /// pose error (docs/notes/tracking.md). Only tracking's estimate against its current keyframe
  /// asks for it: elsewhere only a good estimate (PnP's) is used.
  bool photometric = false;
  /// Motion check: a PnP pose farther than this from the prediction is a bad RANSAC draw and is
  /// not used (the anchors: one bad pose throws the whole trajectory off otherwise).
  double max_jump_m = 0.15;
  double max_jump_deg = 15.0;
  /// The refinement's basin is about a centimetre: it starts from the prior (in steady motion a
  /// constant-velocity prediction is smoother than PnP on a few hundred inliers) when PnP agrees
  /// with it within this; otherwise both are measured against the local map where they are and
  /// the one with the higher NdtRefinementResult::support is refined (the prior in steady
  /// motion, PnP after a jerk or when there is no velocity yet). Refining both and keeping the
  /// better, as before, cost twice the time for no gain beyond the spread other small changes
  /// give (docs/notes/tracking.md).
  double seed_agreement_m = 0.005;
  double seed_agreement_deg = 0.3;
  /// The dense estimate is trusted when at least this share of the associated points are inliers
  /// and at least min_dense_inliers of them ...
  double min_dense_inlier_ratio = 0.5;
  int min_dense_inliers = 300;
  /// ... and the refinement moved the pose less than max_jump from where it started.
};

/// One estimate of T_K_C.
struct RelativePose {
  /// kGood: PnP and the dense refinement agree; kWeak: only one of them is trusted (few
  /// inliers, a large residual, no texture); kLost: neither, the pose is not usable.
  enum class Status { kGood, kWeak, kLost };
  Status status = Status::kLost;
  Transform T_K_C = Transform::Identity();
  int matches = 0;        ///< descriptor matches to keypoints with depth
  int pnp_inliers = 0;    ///< RANSAC inliers (0: PnP not run or failed)
  bool pnp_used = false;  ///< the PnP pose passed the inlier and motion checks and seeded the refinement
  NdtRefinementResult dense;
  bool dense_trusted = false;
  bool usable() const { return status != Status::kLost; }
};

/// Estimates the pose of the frame in keyframe K's frame. `prior_T_K_C` (the constant-velocity
/// prediction, or the current estimate) seeds the refinement when PnP fails and is the reference
/// of the motion check; without a prior PnP must succeed. Deterministic.
RelativePose estimateRelativePose(const Keyframe& K, const TrackingFrame& frame, const PinholeCamera& camera,
                                  const std::optional<Transform>& prior_T_K_C, const RelativePoseParams& params);

/// Translation (m) and rotation (degrees) between two poses.
double translationBetween(const Transform& a, const Transform& b);
double degreesBetween(const Transform& a, const Transform& b);

}  // namespace vdmap
