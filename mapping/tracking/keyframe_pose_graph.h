#pragma once
// The keyframe pose graph of tracked sequences (docs/method.md 9): nodes are the keyframe poses,
// edges the relative poses measured between keyframes (consecutive keyframes, covisibility
// edges, loop edges with a robust loss). After each accepted loop it is optimised and the
// keyframe poses are replaced; the local maps never change, so the global map is rebuilt from
// them and every frame (kept relative to its keyframe) follows.

#include <span>
#include <vector>

#include "mapping/keyframe/keyframe_graph.h"
#include "mapping/posegraph/pose_graph.h"
#include "mapping/tracking/relative_pose.h"

namespace vdmap {

/// Noise added to every measured edge: the dense estimate's own information (its Gauss-Newton
/// normal matrix) counts thousands of points as independent and would claim micrometres; this
/// floor (one sigma) is what a relative pose of two keyframes is really good to.
struct EdgeNoise {
  double translation_m = 0.003;
  double rotation_deg = 0.15;
};

/// When and how loops are closed (PoseSource::kTrack).
struct LoopClosureParams {
  bool enabled = true;
  int min_inliers = 30;  ///< PnP inliers a loop's relative pose needs (besides a good estimate)
  /// How far the drift may have put a revisited keyframe from where tracking expects it.
  double max_drift_m = 0.5;
  double max_drift_deg = 20.0;
  /// A new keyframe that found no loop among its covisible keyframes tries this many other
  /// keyframes whose keypoints could land within candidate_margin_px of its image.
  int candidates = 2;
  double candidate_margin_px = 40.0;
  EdgeNoise edge_noise;
  PoseGraphOptions graph;
};

/// The adjoint of T = (R, t) for perturbations xi = (translation, rotation):
/// T exp(xi) = exp(Ad(T) xi) T, Ad = [[R, [t]x R], [0, R]].
Matrix6d adjoint(const Transform& T);

/// The information matrix of an estimate of T_K_C as a pose-graph edge K -> C (pose_graph.h:
/// right perturbation, translation first): the refinement's normal matrix moved into C's frame,
/// with `floor` added as covariance. An estimate without a trusted refinement gets 3x the floor.
Matrix6d edgeInformation(const RelativePose& estimate, const EdgeNoise& floor = {});

/// The information of a right perturbation of T_A_B moved to the right perturbation of
/// T_A_X = T_A_B * T_B_X.
Matrix6d informationInFrame(const Matrix6d& info_B, const Transform& T_B_X);

/// One accepted loop closure.
struct LoopClosure {
  int frame_index = 0;       ///< the frame that closed it
  int from = 0;              ///< keyframe the frame was tracked in
  int to = 0;                ///< the revisited keyframe
  int inliers = 0;           ///< PnP inliers of the verifying estimate
  double correction_m = 0;   ///< the largest keyframe move the optimisation made
  double pose_graph_ms = 0;  ///< wall time of the optimisation
};

/// Edges and the record of optimisations. Not thread-safe: the mapping thread owns it.
class KeyframePoseGraph {
 public:
  void add(const PoseGraphEdge& edge) { edges_.push_back(edge); }
  std::span<const PoseGraphEdge> edges() const { return edges_; }
  /// Optimises every keyframe pose (keyframe 0 fixed: it anchors the world frame) with
  /// optimizePoseGraph and writes them back with KeyframeGraph::setKeyframePose. Returns the
  /// largest keyframe move (m). The poses before it are kept (posesBeforeOptimisation()).
  /// `keep_before`: posesBeforeOptimisation() stays as it was (a refinement's later rounds).
  double optimise(KeyframeGraph* graph, const PoseGraphOptions& options, PoseGraphResult* result = nullptr,
                  bool keep_before = false);
  /// Adds `edges` (non-robust, measured) in place of the non-robust edges between the same
  /// keyframe pairs (either direction): map_registration.h's map-to-map edges.
  void replaceMeasuredEdges(std::span<const PoseGraphEdge> edges);
  /// Keyframe poses as they were before the last optimisation (empty before the first).
  const std::vector<Transform>& posesBeforeOptimisation() const { return before_; }
  /// The graph's current poses become posesBeforeOptimisation() (an optimisation made elsewhere:
  /// the joint map refinement).
  void keepPosesBefore(const KeyframeGraph& graph) {
    before_.clear();
    for (const Keyframe& k : graph.keyframes()) before_.push_back(k.T_W_K);
  }
  void recordLoop(const LoopClosure& loop) { loops_.push_back(loop); }
  /// Continues a saved graph (its edges and loops; no poses before an optimisation).
  void restore(std::vector<PoseGraphEdge> edges, std::vector<LoopClosure> loops) {
    edges_ = std::move(edges);
    loops_ = std::move(loops);
    before_.clear();
  }
  const std::vector<LoopClosure>& loops() const { return loops_; }

 private:
  std::vector<PoseGraphEdge> edges_;
  std::vector<Transform> before_;
  std::vector<LoopClosure> loops_;
};

}  // namespace vdmap
