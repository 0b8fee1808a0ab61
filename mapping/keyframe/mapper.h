#pragma once
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

/// The per-frame mapping path shared by the command line and the workbench: features,
/// keyframe decision, local-map update. Deterministic. Not thread-safe: one thread feeds it;
/// others may read the graph only while it is not inside addFrame().
class Mapper {
 public:
  explicit Mapper(const PinholeCamera& camera, const MapperParams& params = {});

  /// Maps one frame with its pose. Throws std::invalid_argument when the pose is not a finite
  /// rigid transform or the images do not fit the camera (see LocalMapIntegrator).
  FrameReport addFrame(const RgbdFrame& frame);

  const KeyframeGraph& graph() const { return graph_; }
  KeyframeGraph& graph() { return graph_; }
  const PinholeCamera& camera() const { return camera_; }
  const MapperParams& params() const { return params_; }
  int currentKeyframe() const { return current_; }
  int revisits() const { return revisits_; }
  int framesMapped() const { return frames_; }

 private:
  int newKeyframe(const RgbdFrame& frame, FrameFeatures features);

  PinholeCamera camera_;
  MapperParams params_;
  FeatureExtractor extractor_;
  LocalMapIntegrator integrator_;
  KeyframeGraph graph_;
  KeyframeIndex index_;  ///< rebuilt from graph_ by sync(): nothing of it is saved
  int current_ = -1;
  int revisits_ = 0;
  int frames_ = 0;
};

}  // namespace vdmap
