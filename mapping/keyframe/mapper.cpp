#include "mapping/keyframe/mapper.h"

#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "mapping/core/timing.h"

namespace vdmap {

void MapperParams::validate() const {
  auto check = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(what);
  };
  check(local_map.cell_size_px >= 1, "cell_size must be >= 1 px");
  const DepthRange& d = local_map.depth_range;
  check(d.min_m >= 0 && d.min_m < d.max_m && std::isfinite(d.max_m), "depth range must satisfy 0 <= min < max");
  check(features.orb_features >= 1, "orb_features must be >= 1");
  const KeyframeParams& k = keyframes;
  check(k.tau >= 0 && k.tau <= 1 && k.tau_edge >= 0 && k.tau_edge <= 1, "tau and tau_edge must be within 0..1");
  check(k.prefilter.max_distance_m >= 0 && k.prefilter.max_angle_deg >= 0, "prefilter limits must be >= 0");
  check(k.min_frame_features >= 0, "min_frame_features must be >= 0");
  check(k.covisibility.max_hamming >= 0 && k.covisibility.lowe_ratio > 0 && k.covisibility.lowe_ratio <= 1 &&
            k.covisibility.max_reprojection_px >= 0,
        "covisibility parameters out of range");
  check(keyframe_every >= 0, "keyframe_every must be >= 0");
}

void MapperState::validate(std::size_t keyframes) const {
  if (current_keyframe < -1 || current_keyframe >= static_cast<long long>(keyframes))
    throw std::invalid_argument("current keyframe " + std::to_string(current_keyframe) + " is not one of the " +
                                std::to_string(keyframes) + " keyframes");
  if (frames_mapped < 0 || revisits < 0 || revisits > frames_mapped || last_frame_index < -1)
    throw std::invalid_argument("frame counts must satisfy 0 <= revisits <= frames and the last frame index >= -1");
  if (!std::isfinite(last_timestamp)) throw std::invalid_argument("the last timestamp is not finite");
}

Mapper::Mapper(const PinholeCamera& camera, const MapperParams& params)
    : camera_(camera), params_(params), extractor_(params.features), integrator_(params.local_map) {
  camera_.validate();
  params_.validate();
  // Fail on a bad cell size now rather than at the first keyframe.
  KeyframeContainer(camera_, params_.local_map.cell_size_px);
}

Mapper::Mapper(const PinholeCamera& camera, const MapperParams& params, KeyframeGraph graph, const MapperState& state)
    : Mapper(camera, params) {
  state.validate(graph.size());
  for (const Keyframe& k : graph.keyframes())
    if (k.container.cellSizePx() != params_.local_map.cell_size_px || !(k.container.camera() == camera_))
      throw std::invalid_argument("keyframe " + std::to_string(k.id) +
                                  ": its container does not use the mapper's camera and cell size");
  graph_ = std::move(graph);
  state_ = state;
}

int Mapper::newKeyframe(const RgbdFrame& frame, FrameFeatures features) {
  Keyframe k{0, frame.index, frame.timestamp, frame.T_W_C, CompressedImage(frame.rgb, frame.rgb_file),
             CompressedImage(frame.depth, frame.depth_file),
             std::move(features), KeyframeContainer(camera_, params_.local_map.cell_size_px), 0};
  return graph_.add(std::move(k)).id;
}

std::function<void(RgbdFrame&)> Mapper::featuresAhead() const {
  auto extractor = std::make_shared<const FeatureExtractor>(params_.features);
  return [this, extractor](RgbdFrame& frame) {
    frame.features =
        std::make_shared<const FrameFeatures>(extractor->extract(frame, camera_, params_.local_map.depth_range));
    frame.features_for = this;
  };
}

FrameReport Mapper::addFrame(const RgbdFrame& frame) {
  if (!canContinue())
    throw std::invalid_argument("the session does not store its current keyframe (vdmap session format 1 did not), "
                                "so mapping cannot continue from it; it can still be rendered, exported or opened");
  if (!isValidTransform(frame.T_W_C))
    throw std::invalid_argument("frame " + std::to_string(frame.index) + ": pose is not a finite rigid transform");
  const auto start = std::chrono::steady_clock::now();
  FrameReport report;
  report.frame_index = frame.index;

  FrameFeatures features = frame.features && frame.features_for == this
                               ? *frame.features
                               : extractor_.extract(frame, camera_, params_.local_map.depth_range);
  report.features = features.size();
  report.ms.features_ms = msSince(start);

  const auto decide_start = std::chrono::steady_clock::now();
  const std::vector<KeyframeView> views = graph_.views();
  const int current = state_.current_keyframe;
  if (params_.keyframe_every > 0) {
    const bool start_new = current < 0 || state_.frames_mapped % params_.keyframe_every == 0;
    report.decision.kind = start_new ? FrameDecision::Kind::kNewKeyframe : FrameDecision::Kind::kUpdate;
    report.decision.keyframe = start_new ? -1 : current;
  } else {
    // The current keyframe first; only a frame that lost it asks the index for candidates
    // (the loop-closure search and, for a new keyframe, its edges).
    const std::span<const KeyframeView> current_view =
        current >= 0 ? std::span<const KeyframeView>(&views[current], 1) : std::span<const KeyframeView>();
    report.decision = decideKeyframe(features, frame.T_W_C, current, current_view, camera_, params_.keyframes);
    if (report.decision.kind != FrameDecision::Kind::kUpdate) {
      index_.sync(views);
      const std::vector<KeyframeView> candidates =
          index_.candidates(features, frame.T_W_C, views, params_.keyframes.prefilter, {current});
      report.decision = decideKeyframe(features, frame.T_W_C, current, candidates, camera_, params_.keyframes);
    }
  }
  switch (report.decision.kind) {
    case FrameDecision::Kind::kUpdate:
      report.keyframe = report.decision.keyframe;
      break;
    case FrameDecision::Kind::kRevisit:
      ++state_.revisits;
      report.keyframe = report.decision.keyframe;
      // The frame links the place it left to the place it recognised.
      if (current >= 0) graph_.edges().strengthen(current, report.keyframe, report.decision.delta_current);
      break;
    case FrameDecision::Kind::kNewKeyframe: {
      const auto edges = params_.keyframe_every > 0
                             ? std::vector<std::pair<int, double>>{}
                             : edgesOfNewKeyframe(features, frame.T_W_C, current,
                                                  index_.candidates(features, frame.T_W_C, views,
                                                                    params_.keyframes.prefilter, {current},
                                                                    index_.params().max_edge_candidates),
                                                  camera_, params_.keyframes);
      report.keyframe = newKeyframe(frame, std::move(features));
      for (const auto& [other, weight] : edges) graph_.edges().strengthen(report.keyframe, other, weight);
      if (params_.keyframe_every > 0 && current >= 0) graph_.edges().strengthen(report.keyframe, current, 0.0);
      break;
    }
  }
  state_.current_keyframe = report.keyframe;
  report.ms.decision_ms = msSince(decide_start);

  const auto update_start = std::chrono::steady_clock::now();
  Keyframe& keyframe = graph_.keyframe(state_.current_keyframe);
  integrator_.integrateFrame(frame, camera_, keyframe.T_W_K, &keyframe.container, &report.touched_cells);
  ++keyframe.frames_integrated;
  report.ms.update_ms = msSince(update_start);
  report.ms.total_ms = msSince(start);
  ++state_.frames_mapped;
  state_.last_frame_index = frame.index;
  state_.last_timestamp = frame.timestamp;
  return report;
}

}  // namespace vdmap
