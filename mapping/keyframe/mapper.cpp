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

Mapper::Mapper(const PinholeCamera& camera, const MapperParams& params)
    : camera_(camera), params_(params), extractor_(params.features), integrator_(params.local_map),
      tracker_(params.tracking) {
  camera_.validate();
  params_.validate();
  // Fail on a bad cell size now rather than at the first keyframe.
  KeyframeContainer(camera_, params_.local_map.cell_size_px);
}

int Mapper::newKeyframe(const RgbdFrame& frame, FrameFeatures features) {
  Keyframe k{0, frame.index, frame.timestamp, frame.T_W_C, frame.rgb.clone(), frame.depth.clone(),
             std::move(features), KeyframeContainer(camera_, params_.local_map.cell_size_px), 0};
  return graph_.add(std::move(k)).id;
}

std::vector<StampedPose> Mapper::trajectory() const {
  std::vector<StampedPose> out;
  out.reserve(frame_poses_.size());
  for (const FramePose& f : frame_poses_) out.push_back({f.timestamp, graph_.keyframe(f.keyframe).T_W_K * f.T_K_C});
  return out;
}

bool Mapper::trackFrame(const FrameFeatures& features, RgbdFrame* frame, FrameReport* report) {
  // The first frame anchors the world frame at its given pose (the ground truth's when the
  // sequence has one, so maps and trajectories overlay it; else the identity).
  if (current_ < 0) return true;
  const DensePoints points = sampleDensePoints(*frame, camera_, params_.local_map.depth_range,
                                               params_.tracking.relative.dense.stride_px);
  const TrackingOutcome outcome =
      tracker_.track(graph_, current_, {&features, &points}, camera_, params_.keyframes.prefilter);
  report->weak = outcome.weak;
  report->relocalised = outcome.relocalised;
  if (outcome.lost()) {
    tracker_.lose();
    ++frames_lost_;
    report->lost = true;
    return false;
  }
  frame->T_W_C = graph_.keyframe(outcome.keyframe).T_W_K * outcome.estimate.T_K_C;
  return true;
}

FrameReport Mapper::addFrame(const RgbdFrame& input) {
  const bool tracking = params_.poses == PoseSource::kTrack;
  if (!isValidTransform(input.T_W_C))
    throw std::invalid_argument("frame " + std::to_string(input.index) + ": pose is not a finite rigid transform");
  const auto start = std::chrono::steady_clock::now();
  FrameReport report;
  report.frame_index = input.index;

  FrameFeatures features = extractor_.extract(input, camera_, params_.local_map.depth_range);
  report.features = features.size();
  report.ms.features_ms = msSince(start);

  RgbdFrame frame = input;  // shares the images; only the pose may change
  if (tracking) {
    const auto track_start = std::chrono::steady_clock::now();
    const bool placed = trackFrame(features, &frame, &report);
    report.ms.tracking_ms = msSince(track_start);
    if (!placed) {
      ++frames_;
      report.ms.total_ms = msSince(start);
      return report;
    }
  }
  report.T_W_C = frame.T_W_C;

  const auto decide_start = std::chrono::steady_clock::now();
  const std::vector<KeyframeView> views = graph_.views();
  if (params_.keyframe_every > 0) {
    const bool start_new = current_ < 0 || frames_ % params_.keyframe_every == 0;
    report.decision.kind = start_new ? FrameDecision::Kind::kNewKeyframe : FrameDecision::Kind::kUpdate;
    report.decision.keyframe = start_new ? -1 : current_;
  } else {
    report.decision = decideKeyframe(features, frame.T_W_C, current_, views, camera_, params_.keyframes);
  }
  switch (report.decision.kind) {
    case FrameDecision::Kind::kUpdate:
      report.keyframe = report.decision.keyframe;
      break;
    case FrameDecision::Kind::kRevisit:
      ++revisits_;
      report.keyframe = report.decision.keyframe;
      // The frame links the place it left to the place it recognised.
      if (current_ >= 0) graph_.edges().strengthen(current_, report.keyframe, report.decision.delta_current);
      break;
    case FrameDecision::Kind::kNewKeyframe: {
      const auto edges = params_.keyframe_every > 0
                             ? std::vector<std::pair<int, double>>{}
                             : edgesOfNewKeyframe(features, frame.T_W_C, current_, views, camera_, params_.keyframes);
      report.keyframe = newKeyframe(frame, std::move(features));
      for (const auto& [other, weight] : edges) graph_.edges().strengthen(report.keyframe, other, weight);
      if (params_.keyframe_every > 0 && current_ >= 0) graph_.edges().strengthen(report.keyframe, current_, 0.0);
      break;
    }
  }
  current_ = report.keyframe;
  report.ms.decision_ms = msSince(decide_start);

  const auto update_start = std::chrono::steady_clock::now();
  Keyframe& keyframe = graph_.keyframe(current_);
  integrator_.integrateFrame(frame, camera_, keyframe.T_W_K, &keyframe.container, &report.touched_cells);
  ++keyframe.frames_integrated;
  report.ms.update_ms = msSince(update_start);
  const Transform T_K_C = keyframe.T_W_K.inverse() * frame.T_W_C;
  frame_poses_.push_back({frame.index, frame.timestamp, current_, T_K_C});
  if (tracking) tracker_.accept(graph_, current_, T_K_C);
  report.ms.total_ms = msSince(start);
  ++frames_;
  return report;
}

}  // namespace vdmap
