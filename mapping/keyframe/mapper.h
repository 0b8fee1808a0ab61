#pragma once
#include <functional>
#include <vector>

#include "mapping/keyframe/keyframe_graph.h"
#include "mapping/keyframe/keyframe_index.h"
#include "mapping/local_map/local_map_integrator.h"

namespace vdmap {

/// Everything that shapes the local maps and the graph; changing any of it means re-running
/// the sequence (SPEC section 9, "no" in the live column).
struct MapperParams {
  LocalMapParams local_map;
  FeatureParams features;
  KeyframeParams keyframes;
  /// > 0: every N-th frame starts a keyframe and covisibility is not consulted (a fixed
  /// schedule, for comparisons); 0: the covisibility decision of SPEC section 5.
  int keyframe_every = 0;

  /// Throws std::invalid_argument naming the first value out of range (the cell size is checked
  /// against the camera by Mapper).
  void validate() const;
};

/// Wall time of each stage of one frame, milliseconds.
struct StageTimes {
  double features_ms = 0;
  double decision_ms = 0;  ///< covisibility against the current keyframe, loop search, edges
  double update_ms = 0;    ///< local-map integration
  double total_ms = 0;
};

/// What happened to one frame.
struct FrameReport {
  int frame_index = 0;
  FrameDecision decision;   ///< kind, deltas, and the search's matched / pruned counts
  int keyframe = -1;        ///< the keyframe the frame went into (new or existing)
  std::size_t features = 0;
  std::vector<int> touched_cells;  ///< grid indices of `keyframe`'s container that changed
  StageTimes ms;
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
  int last_frame_index = -1;  ///< depth-list index of the last frame mapped (-1: none)
  double last_timestamp = 0;  ///< s, its depth timestamp

  /// Throws std::invalid_argument when a field is out of range for a graph of `keyframes` keyframes.
  void validate(std::size_t keyframes) const;
};

/// The per-frame mapping path shared by the command line and the workbench: features,
/// keyframe decision, local-map update. Deterministic. Not thread-safe: one thread feeds it;
/// others may read the graph only while it is not inside addFrame().
class Mapper {
 public:
  explicit Mapper(const PinholeCamera& camera, const MapperParams& params = {});
  /// Continues a run that stopped with `graph` and `state` (a loaded session): the next frame is
  /// mapped as it would have been in the run that made them (when canContinue()). Throws
  /// std::invalid_argument when the state does not fit the graph, or a keyframe's container does
  /// not use `camera` and the cell size.
  Mapper(const PinholeCamera& camera, const MapperParams& params, KeyframeGraph graph, const MapperState& state);

  /// Maps one frame with its pose. Throws std::invalid_argument when the pose is not a finite
  /// rigid transform, the images do not fit the camera (see LocalMapIntegrator), or the mapper
  /// cannot continue (canContinue()).
  FrameReport addFrame(const RgbdFrame& frame);

  /// A function that computes a frame's features exactly as addFrame() would, for another
  /// thread (a FramePrefetcher's: ORB then overlaps mapping, issue 16). It holds its own
  /// extractor, so it may run beside addFrame(); the Mapper must outlive it.
  std::function<void(RgbdFrame&)> featuresAhead() const;

  const KeyframeGraph& graph() const { return graph_; }
  KeyframeGraph& graph() { return graph_; }
  const PinholeCamera& camera() const { return camera_; }
  const MapperParams& params() const { return params_; }
  int currentKeyframe() const { return state_.current_keyframe; }
  int revisits() const { return state_.revisits; }
  int framesMapped() const { return state_.frames_mapped; }
  const MapperState& state() const { return state_; }
  /// False for keyframes restored without their current keyframe (a format-1 session): they
  /// can be viewed and exported, not mapped further.
  bool canContinue() const { return graph_.size() == 0 || state_.current_keyframe >= 0; }

 private:
  int newKeyframe(const RgbdFrame& frame, FrameFeatures features);

  PinholeCamera camera_;
  MapperParams params_;
  FeatureExtractor extractor_;
  LocalMapIntegrator integrator_;
  KeyframeGraph graph_;
  MapperState state_;
  KeyframeIndex index_;  ///< rebuilt from graph_ by sync(): nothing of it is saved
};

}  // namespace vdmap
