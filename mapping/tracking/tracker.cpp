#include "mapping/tracking/tracker.h"

#include <algorithm>
#include <vector>

namespace vdmap {

std::optional<Transform> Tracker::predict(const KeyframeGraph& graph) const {
  if (state_.keyframe < 0) return std::nullopt;
  return graph.keyframe(state_.keyframe).T_W_K * state_.T_K_C * state_.velocity;
}

TrackingOutcome Tracker::track(const KeyframeGraph& graph, int current, const TrackingFrame& frame,
                               const PinholeCamera& camera, const PosePrefilter& prefilter,
                               std::span<const int> recognised) const {
  TrackingOutcome out;
  const std::optional<Transform> T_W_pred = predict(graph);
  // After lost frames the camera may have moved further than one frame's motion.
  RelativePoseParams params = params_.relative;
  params.max_jump_m *= 1 + state_.frames_lost;
  params.max_jump_deg *= 1 + state_.frames_lost;
  // ... and the prediction may be so far off that matches by projection pair wrong keypoints:
  // brute-force matching and RANSAC until a frame is placed again.
  if (state_.frames_lost > 0) params.pnp.search_radius_px = 0;
  const auto prior = [&](const Keyframe& K) -> std::optional<Transform> {
    if (!T_W_pred) return std::nullopt;
    return K.T_W_K.inverse() * *T_W_pred;
  };
  const Keyframe& K = graph.keyframe(current);
  RelativePoseParams current_params = params;
  current_params.photometric = params_.photometric;
  out.estimate = estimateRelativePose(K, frame, camera, prior(K), current_params);
  if (out.estimate.status == RelativePose::Status::kGood) {
    out.keyframe = current;
    return out;
  }
  out.weak = true;
  if (T_W_pred && params_.relocalisation_candidates > 0) {
    // The revisit search's candidates at the predicted pose: pre-filtered, best bound first.
    std::vector<std::pair<double, int>> candidates;
    for (const Keyframe& other : graph.keyframes()) {
      if (other.id == current || !prefilter.accepts(other.T_W_K, *T_W_pred)) continue;
      const double bound = covisibilityBound(other.features, other.T_W_K, *T_W_pred, camera);
      if (bound > 0) candidates.emplace_back(-bound, other.id);
    }
    std::sort(candidates.begin(), candidates.end());
    if (candidates.size() > static_cast<std::size_t>(params_.relocalisation_candidates))
      candidates.resize(static_cast<std::size_t>(params_.relocalisation_candidates));
    if (state_.frames_lost > 0) {
      int proposed = 0;
      for (const int id : recognised) {
        if (proposed >= params_.recognition_candidates) break;
        if (id == current ||
            std::any_of(candidates.begin(), candidates.end(), [id](const auto& c) { return c.second == id; }))
          continue;
        candidates.emplace_back(1.0, id);  // after the pose-based ones; no prior (see below)
        ++proposed;
      }
    }
    for (const auto& [negative_bound, id] : candidates) {
      const Keyframe& R = graph.keyframe(id);
      // A recognised place is estimated without the stale prediction: PnP RANSAC decides alone.
      const bool recognised_place = negative_bound > 0;
      RelativePose estimate =
          estimateRelativePose(R, frame, camera, recognised_place ? std::nullopt : prior(R), params);
      if (estimate.status == RelativePose::Status::kGood) {
        out.estimate = std::move(estimate);
        out.keyframe = id;
        out.relocalised = true;
        return out;
      }
    }
  }
  // A weak estimate continues the track; after lost frames, whose prediction is stale, it is
  // as likely a wrong place that fits (the box-like rooms of the built-in scene): not used; nor
  // is the local map's alone when it explains only a patch of the frame or leaves it free to slide.
  const RelativePose& e = out.estimate;
  const bool supported =
      e.pnp_used || (e.dense.inliers >= params_.min_dense_only_share * static_cast<double>(e.dense.points) &&
                     e.dense.translationConditioning() >= params_.min_dense_only_conditioning);
  if (e.usable() && supported && state_.frames_lost == 0) out.keyframe = current;
  return out;
}

void Tracker::accept(const KeyframeGraph& graph, int keyframe, const Transform& T_K_C) {
  if (state_.keyframe >= 0 && state_.frames_lost == 0) {
    const Transform T_W_prev = graph.keyframe(state_.keyframe).T_W_K * state_.T_K_C;
    const Transform T_W_cur = graph.keyframe(keyframe).T_W_K * T_K_C;
    state_.velocity = T_W_prev.inverse() * T_W_cur;
  } else {
    state_.velocity = Transform::Identity();
  }
  state_.keyframe = keyframe;
  state_.T_K_C = T_K_C;
  state_.frames_lost = 0;
}

}  // namespace vdmap
