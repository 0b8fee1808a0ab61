#pragma once
// Keyframe poses from their settled local maps, after the last frame (tracked poses). An edge
// measured when a keyframe was created compares one frame with a map; the settled maps average
// every frame of both keyframes. kJoint (the default) optimises every keyframe pose at once on
// the sum of the covisible pairs' map-to-map costs (one keyframe's ellipsoid means against the
// other's distributions, docs/method.md 10's dense objective); kPairwise registers each pair on its
// own, those relative poses replace the pair's frame-measured pose-graph edges, and the graph is
// optimised, in rounds. A single pair's registration is no better than tracking; only summed in
// one cost do the pairs' errors average out, so on the built-in walk the joint refinement brings
// the map closer to the mesh and the pairwise one takes it farther (docs/results.md has the
// figures, docs/notes/tracking.md their history).

#include <optional>

#include "mapping/keyframe/keyframe_graph.h"
#include "mapping/tracking/keyframe_pose_graph.h"

namespace vdmap {

enum class MapRefinementMethod {
  /// Each covisible pair registered on its own, its relative pose an edge of the pose graph,
  /// which is then optimised; in rounds. Each edge is claimed with a 1 mm floor, tighter than a
  /// pair's error from the truth on the built-in walk, so the map can end worse than tracked.
  kPairwise,
  /// Every keyframe pose at once on the sum of the covisible pairs' costs (Levenberg-Marquardt):
  /// a pair's directions its surfaces leave free are held by the other pairs instead of by an
  /// edge's guessed information. The cells without the sensor's axial noise
  /// (NdtRefinementParams::axial_noise): the means are averages.
  kJoint,
};

struct MapRefinementParams {
  MapRefinementMethod method = MapRefinementMethod::kJoint;
  /// The registration's dense refinement (tracking's, with 20 Gauss-Newton steps instead of 6:
  /// with 6 the Replica office0 map ended farther from the mesh, docs/notes/tracking.md), and its
  /// checks: at least min_dense_inliers inlier cells making min_dense_inlier_ratio of those
  /// associated, a move of at most max_jump from the graph's relative pose (kJoint: no covisible
  /// pair's relative pose may change more, else the refinement is refused).
  RelativePoseParams relative = [] {
    RelativePoseParams p;
    p.dense.iterations = 20;
    p.max_jump_m = 0.03;
    p.max_jump_deg = 2.0;
    return p;
  }();
  int min_cell_points = 20;  ///< cells of B with fewer points are not aligned
  /// Smallest over largest eigenvalue of the registration's normal matrix in translation: below
  /// it the maps do not pin a direction (two walls: a box-room keyframe slid the wrong way at a
  /// lower bound) and the pair gives no edge. It sits at the top of the scores of box-room pairs
  /// that see only walls and below those of Replica's and 7-Scenes' pairs (docs/notes/tracking.md).
  double min_conditioning = 0.03;
  /// Noise floor of a map-to-map edge (one sigma), added to the registration's own information.
  EdgeNoise edge_noise{0.001, 0.05};
  int max_rounds = 5;
  double converged_m = 0.0005;  ///< stop when a round moves no keyframe farther than this
  /// kJoint: the cost of a pair (B's means against A's cells, those within robust_k at the
  /// starting poses; no annealing), and the Levenberg-Marquardt steps at most. A step is taken
  /// only when it lowers the cost (the pairs' Tukey losses and the pose graph's measured edges;
  /// a rejected one raises the damping); converged when no keyframe moves more than
  /// joint_converged_m.
  NdtRefinementParams joint = [] {
    NdtRefinementParams p;
    p.axial_noise = false;
    return p;
  }();
  int joint_iterations = 100;
  double joint_converged_m = 1e-5;
  int threads = 0;  ///< registrations in parallel (0: all cores); the result does not depend on it
};

/// Refines T_A_B from the keyframes' current poses by aligning B's local map (its ellipsoid
/// means) to A's (the dense refinement, no features): the edge A -> B, or nullopt when the
/// registration is not trusted (too few inliers, moved too far, ill-conditioned).
std::optional<PoseGraphEdge> registerLocalMaps(const Keyframe& A, const Keyframe& B, const MapRefinementParams& params);

struct MapRefinementResult {
  int pairs = 0;       ///< covisible keyframe pairs registered (last round)
  int edges = 0;       ///< of those, trusted: map-to-map edges in the graph
  int rounds = 0;      ///< pose-graph rounds (kPairwise) or steps taken (kJoint)
  double moved_m = 0;  ///< the largest keyframe move of the whole refinement
  double ms = 0;       ///< wall time
  /// kJoint: a covisible pair's relative pose would have changed by more than relative.max_jump,
  /// so the poses and the pose graph were left as they were.
  bool refused = false;
};

/// kPairwise: registers every covisible pair of `graph` (a round), replaces the pose graph's
/// frame-measured edges of those pairs with the map-to-map ones, optimises the keyframe poses
/// (keyframe 0 fixed) and repeats until converged. kJoint: optimises the keyframe poses
/// (keyframe 0 fixed) on all pairs' costs at once, then replaces those pairs' edges with the
/// relative poses reached, so a later optimisation keeps them. Loop edges stay. Deterministic
/// whatever `threads`.
MapRefinementResult refineKeyframePoses(KeyframeGraph* graph, KeyframePoseGraph* pose_graph,
                                        const PoseGraphOptions& options, const MapRefinementParams& params = {});

}  // namespace vdmap
