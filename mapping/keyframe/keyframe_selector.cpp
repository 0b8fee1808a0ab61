#include "mapping/keyframe/keyframe_selector.h"

#include <algorithm>

namespace vdmap {
namespace {

struct Candidate {
  double bound;
  const KeyframeView* keyframe;
};

// Keyframes other than `skip` that pass the pre-filter and whose bound reaches `threshold`,
// most promising first (ties: lower id first, so the search order is deterministic).
std::vector<Candidate> candidates(std::span<const KeyframeView> keyframes, int skip, const Transform& T_W_F,
                                  double threshold, const PinholeCamera& camera, const KeyframeParams& params,
                                  int* pruned) {
  std::vector<Candidate> out;
  for (const KeyframeView& k : keyframes) {
    if (k.id == skip) continue;
    double bound = 0.0;
    if (params.prefilter.accepts(*k.T_W_K, T_W_F))
      bound = covisibilityBound(*k.features, *k.T_W_K, T_W_F, camera, params.covisibility);
    if (bound < threshold || bound == 0.0) {
      ++*pruned;
      continue;
    }
    out.push_back({bound, &k});
  }
  std::sort(out.begin(), out.end(), [](const Candidate& a, const Candidate& b) {
    return a.bound != b.bound ? a.bound > b.bound : a.keyframe->id < b.keyframe->id;
  });
  return out;
}

}  // namespace

FrameDecision decideKeyframe(const FrameFeatures& frame, const Transform& T_W_F, int current,
                             std::span<const KeyframeView> keyframes, const PinholeCamera& camera,
                             const KeyframeParams& params, CovisibilityMeasure measure) {
  FrameDecision decision;
  for (const KeyframeView& k : keyframes) {
    if (k.id != current) continue;
    if (static_cast<int>(frame.size()) < params.min_frame_features) {
      if (params.prefilter.accepts(*k.T_W_K, T_W_F)) {
        decision.kind = FrameDecision::Kind::kUpdate;
        decision.keyframe = current;
      }
      return decision;
    }
    decision.delta_current = measure(*k.features, *k.T_W_K, frame, T_W_F, camera, params.covisibility);
    ++decision.matched;
    if (decision.delta_current >= params.tau) {
      decision.kind = FrameDecision::Kind::kUpdate;
      decision.keyframe = current;
      return decision;
    }
  }
  int best_id = -1;
  for (const Candidate& c : candidates(keyframes, current, T_W_F, params.tau, camera, params, &decision.pruned)) {
    // Bounds only fall from here on; one below the best cannot win (an equal one can, on id).
    if (best_id >= 0 &&
        (c.bound < decision.delta_best || (c.bound == decision.delta_best && c.keyframe->id > best_id))) {
      ++decision.pruned;
      continue;
    }
    const double delta = measure(*c.keyframe->features, *c.keyframe->T_W_K, frame, T_W_F, camera, params.covisibility);
    ++decision.matched;
    if (delta >= params.tau &&
        (best_id < 0 || delta > decision.delta_best || (delta == decision.delta_best && c.keyframe->id < best_id))) {
      decision.delta_best = delta;
      best_id = c.keyframe->id;
    }
  }
  if (best_id >= 0) {
    decision.kind = FrameDecision::Kind::kRevisit;
    decision.keyframe = best_id;
  }
  return decision;
}

std::vector<std::pair<int, double>> edgesOfNewKeyframe(const FrameFeatures& features, const Transform& T_W_N,
                                                       int previous, std::span<const KeyframeView> keyframes,
                                                       const PinholeCamera& camera, const KeyframeParams& params,
                                                       CovisibilityMeasure measure) {
  std::vector<std::pair<int, double>> edges;
  for (const KeyframeView& k : keyframes) {
    const bool is_previous = k.id == previous;
    if (!is_previous && !params.prefilter.accepts(*k.T_W_K, T_W_N)) continue;
    if (!is_previous && covisibilityBound(*k.features, *k.T_W_K, T_W_N, camera, params.covisibility) < params.tau_edge)
      continue;
    const double delta = measure(*k.features, *k.T_W_K, features, T_W_N, camera, params.covisibility);
    if (is_previous || delta >= params.tau_edge) edges.emplace_back(k.id, delta);
  }
  std::sort(edges.begin(), edges.end());
  return edges;
}

}  // namespace vdmap
