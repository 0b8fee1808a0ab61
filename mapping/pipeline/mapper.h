#pragma once
#include <chrono>
#include <functional>
#include <optional>
#include <span>
#include <vector>

#include "mapping/io/trajectory_io.h"
#include "mapping/keyframe/keyframe_graph.h"
#include "mapping/keyframe/keyframe_index.h"
#include "mapping/local_map/local_map_integrator.h"
#include "mapping/tracking/keyframe_pose_graph.h"
#include "mapping/tracking/map_registration.h"
#include "mapping/tracking/tracker.h"

namespace vdmap {

/// Where frame poses come from.
enum class PoseSource {
  kGroundTruth,  ///< each frame's T_W_C as given (the sequence's groundtruth.txt)
  kTrack,        ///< estimated by the Tracker (docs/method.md 8); the given T_W_C is ignored
                 ///< except the first frame's, which anchors the world frame
};

/// Everything that shapes the local maps and the graph; changing any of it means re-running
/// the sequence (docs/parameters.md, "no" in the live column).
struct MapperParams {
  LocalMapParams local_map;
  FeatureParams features;
  KeyframeParams keyframes;
  /// > 0: every N-th frame starts a keyframe and covisibility is not consulted (a fixed
  /// schedule, for comparisons); 0: the covisibility decision of docs/method.md 5.
  int keyframe_every = 0;
  PoseSource poses = PoseSource::kGroundTruth;

  /// Throws std::invalid_argument naming the first value out of range (the cell size is checked
  /// against the camera by Mapper). The ranges are the parameter table's (mapper_parameters.cpp).
  void validate() const;
};

/// How poses are tracked and loops closed (PoseSource::kTrack). Not user settings: sessions do
/// not store them; tests and experiments pass others to the Mapper.
struct TrackingParams {
  TrackerParams tracker;
  LoopClosureParams loops;
};

/// Wall time of each stage of one frame, milliseconds.
struct StageTimes {
  double features_ms = 0;    ///< ORB, on this thread or, computed ahead, on the prefetch thread (then not in total_ms)
  double decision_ms = 0;    ///< covisibility against the current keyframe, loop search, edges
  double update_ms = 0;      ///< local-map integration
  double tracking_ms = 0;    ///< pose estimate (PoseSource::kTrack): dense sampling, PnP, refinement
  double pose_graph_ms = 0;  ///< pose-graph optimisation after a loop closure (part of decision_ms)
  double total_ms = 0;
};

/// What happened to one frame.
struct FrameReport {
  int frame_index = 0;
  FrameDecision decision;  ///< kind, deltas, and the search's matched / pruned counts
  int keyframe = -1;       ///< the keyframe the frame went into (new or existing)
  std::size_t features = 0;
  std::vector<int> touched_cells;           ///< grid indices of `keyframe`'s container that changed
  Transform T_W_C = Transform::Identity();  ///< the pose the frame was mapped at
  /// PoseSource::kTrack: the current keyframe gave a weak estimate (few inliers, a large residual)
  bool weak = false;
  bool relocalised = false;  ///< placed against another keyframe than the current one
  /// The frame could not be placed: nothing was integrated, `keyframe` is -1.
  bool lost = false;
  /// The frame's depth went into `keyframe`'s local map. False for a frame placed on a weak
  /// estimate (weak and not relocalised) that does not start a keyframe: its pose is in the
  /// trajectory, its depth nowhere.
  bool integrated = false;
  /// A loop was closed: the keyframe poses were optimised (the global map needs a rebuild).
  bool loop_closed = false;
  double loop_correction_m = 0;  ///< the largest keyframe move of that optimisation
  StageTimes ms;
};

/// A mapped frame's pose relative to the keyframe it went into.
struct FramePose {
  int frame_index = 0;
  double timestamp = 0;
  int keyframe = 0;
  Transform T_K_C = Transform::Identity();
};

/// What a Mapper carries from one frame to the next besides its graph: with the graph and the
/// parameters it is everything needed to go on mapping exactly as if the run had not stopped
/// (a session file stores it, session_file.h). Per-frame state that a later stage adds (a
/// tracker's velocity, the last pose) belongs here, with its field in the session file.
struct MapperState {
  /// The keyframe the last frame went into; -1 before the first frame (or unknown: a session of
  /// format 1, which cannot be continued).
  int current_keyframe = -1;
  int frames_mapped = 0;
  int revisits = 0;
  int last_frame_index = -1;   ///< depth-list index of the last frame mapped (-1: none)
  double last_timestamp = 0;   ///< s, its depth timestamp
  int frames_lost = 0;         ///< frames PoseSource::kTrack could not place (skipped, not integrated)
  int frames_weak = 0;         ///< placed on the current keyframe's weak estimate (not relocalised)
  int frames_relocalised = 0;  ///< placed against another keyframe after a weak estimate
  /// One pose per placed frame (integrated or not), relative to the keyframe it was placed in, so
  /// the trajectory follows every keyframe pose correction.
  std::vector<FramePose> frame_poses;
  // PoseSource::kTrack: the tracker's motion state and the keyframe pose graph (its edges and
  // the loops closed so far); the poses before the last optimisation are not kept.
  TrackerState tracker;
  std::vector<PoseGraphEdge> pose_graph_edges;
  std::vector<LoopClosure> loops;

  /// Throws std::invalid_argument when a field is out of range for a graph of `keyframes` keyframes.
  void validate(std::size_t keyframes) const;
};

/// The per-frame mapping path shared by the command line and the workbench: features,
/// keyframe decision, local-map update. Deterministic. Not thread-safe: one thread feeds it;
/// others may read the graph only while it is not inside addFrame().
class Mapper {
 public:
  explicit Mapper(const PinholeCamera& camera, const MapperParams& params = {}, const TrackingParams& tracking = {});
  /// Continues a run that stopped with `graph` and `state` (a loaded session): the next frame is
  /// mapped as it would have been in the run that made them (when canContinue()). Throws
  /// std::invalid_argument when the state does not fit the graph, or a keyframe's container does
  /// not use `camera` and the cell size.
  Mapper(const PinholeCamera& camera, const MapperParams& params, KeyframeGraph graph, const MapperState& state,
         const TrackingParams& tracking = {});

  /// Maps one frame with its pose (PoseSource::kGroundTruth) or at the pose the tracker
  /// estimates (kTrack; a frame it cannot place is skipped: FrameReport::lost). Throws
  /// std::invalid_argument when a given pose is not a finite rigid transform, the images do not
  /// fit the camera (see LocalMapIntegrator), or the mapper cannot continue (canContinue()).
  FrameReport addFrame(const RgbdFrame& frame);

  /// A function that computes a frame's features exactly as addFrame() would, for another
  /// thread (a FramePrefetcher's: ORB then overlaps mapping). It holds its own
  /// extractor, so it may run beside addFrame(); the Mapper must outlive it.
  std::function<void(RgbdFrame&)> featuresAhead() const;

  const KeyframeGraph& graph() const { return graph_; }
  KeyframeGraph& graph() { return graph_; }
  const PinholeCamera& camera() const { return camera_; }
  const MapperParams& params() const { return params_; }
  int currentKeyframe() const { return state_.current_keyframe; }
  int revisits() const { return state_.revisits; }
  /// Frames fed to addFrame(), lost ones included.
  int framesMapped() const { return state_.frames_mapped; }
  int framesLost() const { return state_.frames_lost; }
  /// PoseSource::kTrack, frames of the whole run (saved with a session since format 5): placed
  /// on the current keyframe's weak estimate (PnP or the dense refinement not trusted), and placed
  /// against another keyframe after one (relocalised). Frames lost, weak and relocalised are
  /// disjoint.
  int framesWeak() const { return state_.frames_weak; }
  int framesRelocalised() const { return state_.frames_relocalised; }
  /// The state to save: the counters, the tracker's and the pose graph's.
  MapperState state() const;
  /// False for keyframes restored without their current keyframe (a format-1 session): they
  /// can be viewed and exported, not mapped further.
  bool canContinue() const { return graph_.size() == 0 || state_.current_keyframe >= 0; }
  const std::vector<FramePose>& framePoses() const { return state_.frame_poses; }
  /// The world poses of framePoses() with the keyframes' current poses, as a TUM trajectory.
  std::vector<StampedPose> trajectory() const;
  const Tracker& tracker() const { return tracker_; }
  /// PoseSource::kTrack: the keyframe pose graph, its loop closures and the poses before the
  /// last optimisation.
  const KeyframePoseGraph& poseGraph() const { return pose_graph_; }
  /// PoseSource::kTrack, when the sequence has been mapped: registers the local maps of covisible
  /// keyframes and optimises the keyframe poses with those edges (map_registration.h). Frames
  /// follow their keyframes; the global map needs a rebuild.
  MapRefinementResult refineKeyframePoses(const MapRefinementParams& params = {});

 private:
  // A loop edge added to the pose graph for a new keyframe: the keyframe it reaches with the most
  // PnP inliers (`closed` may hold with `to` -1 when no loop edge had an inlier).
  struct LoopEdge {
    bool closed = false;
    int to = -1;
    int inliers = 0;
  };

  bool tracksPoses() const { return params_.poses == PoseSource::kTrack; }
  // Throws std::invalid_argument when the mapper cannot continue or the frame's pose is not rigid.
  void checkCanMap(const RgbdFrame& input) const;
  // addFrame's steps, in order. The frame's features: computed ahead (featuresAhead) or here,
  // timed from `start`.
  FrameFeatures frameFeatures(const RgbdFrame& input, std::chrono::steady_clock::time_point start, FrameReport* report);
  // PoseSource::kTrack: samples the frame's dense points into `points` (`observed` reads them) and
  // places the frame (trackFrame), timed.
  std::optional<TrackingOutcome> placeFrame(const TrackingFrame& observed, DensePoints* points, RgbdFrame* frame,
                                            FrameReport* report);
  // Update, revisit or new keyframe: the fixed schedule (keyframe_every), else covisibility with
  // the current keyframe and, when that fails, with the index's candidates.
  FrameDecision decideFrame(const FrameFeatures& features, const Transform& T_W_C,
                            const std::vector<KeyframeView>& views);
  // FrameDecision::Kind::kRevisit: counts it, closes a loop when the place is not linked to the
  // current keyframe, and links the two.
  void revisitKeyframe(const TrackingFrame& observed, RgbdFrame* frame, FrameReport* report);
  // FrameDecision::Kind::kNewKeyframe: the keyframe (keeping `features`), its covisibility edges
  // and, with tracked poses, its pose-graph edges.
  void startKeyframe(FrameFeatures features, const DensePoints& points, const TrackingOutcome& tracked,
                     const std::vector<KeyframeView>& views, RgbdFrame* frame, FrameReport* report);
  // The frame's depth into the current keyframe's local map, unless it was placed on a weak estimate.
  void updateLocalMap(const RgbdFrame& frame, const TrackingOutcome& tracked, FrameReport* report);
  // The frame's pose in the current keyframe, for the trajectory and the tracker.
  void recordPose(const RgbdFrame& frame);
  void countFrame(const RgbdFrame& frame);

  int newKeyframe(const RgbdFrame& frame, FrameFeatures features);
  // PoseSource::kTrack: sets frame->T_W_C (nullopt: the frame cannot be placed).
  std::optional<TrackingOutcome> trackFrame(const TrackingFrame& observed, RgbdFrame* frame, FrameReport* report);
  RelativePoseParams loopEstimateParams() const;
  // Optimises the pose graph and puts the frame at T_K_C in `keyframe`'s corrected pose.
  void optimisePoseGraph(RgbdFrame* frame, int keyframe, const Transform& T_K_C, FrameReport* report);
  // A revisit of a keyframe that is no neighbour of the current one: measure, verify, add the
  // loop edge, optimise. False when the estimate is not good enough (the revisit stands).
  bool closeLoop(int revisited, const TrackingFrame& observed, RgbdFrame* frame, FrameReport* report);
  // The pose-graph edges of a new keyframe: from the keyframe it was tracked in, and measured
  // ones to its covisible keyframes (loop edges for those the previous keyframe is not linked to).
  void addKeyframeEdges(int created, int previous, const TrackingOutcome& tracked,
                        std::span<const std::pair<int, double>> covisible, const TrackingFrame& observed,
                        RgbdFrame* frame, FrameReport* report);
  // addKeyframeEdges' measured edges to the covisible keyframes.
  LoopEdge addCovisibleEdges(int created, int previous, const TrackingOutcome& tracked,
                             std::span<const std::pair<int, double>> covisible, const TrackingFrame& observed,
                             const RgbdFrame& frame);
  // addKeyframeEdges when no covisible keyframe closed a loop: the first verified of the keyframes
  // whose features could project into the frame with a drift-sized margin.
  LoopEdge addLoopEdgeBeyondCovisibility(int created, int previous, const TrackingFrame& observed,
                                         const RgbdFrame& frame);

  PinholeCamera camera_;
  MapperParams params_;
  TrackingParams tracking_;
  FeatureExtractor extractor_;
  LocalMapIntegrator integrator_;
  KeyframeGraph graph_;
  MapperState state_;
  KeyframeIndex index_;  ///< rebuilt from graph_ by sync(): nothing of it is saved
  Tracker tracker_;
  KeyframePoseGraph pose_graph_;
};

}  // namespace vdmap
