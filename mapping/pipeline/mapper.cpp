#include "mapping/pipeline/mapper.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

#include "mapping/core/timing.h"
#include "mapping/tracking/ndt_refinement.h"

namespace vdmap {

void MapperState::validate(std::size_t keyframes) const {
  if (current_keyframe < -1 || current_keyframe >= static_cast<long long>(keyframes))
    throw std::invalid_argument("current keyframe " + std::to_string(current_keyframe) + " is not one of the " +
                                std::to_string(keyframes) + " keyframes");
  if (frames_mapped < 0 || revisits < 0 || revisits > frames_mapped || last_frame_index < -1)
    throw std::invalid_argument("frame counts must satisfy 0 <= revisits <= frames and the last frame index >= -1");
  if (!std::isfinite(last_timestamp)) throw std::invalid_argument("the last timestamp is not finite");
  if (frames_lost < 0 || frames_lost + revisits > frames_mapped ||
      frame_poses.size() + static_cast<std::size_t>(frames_lost) > static_cast<std::size_t>(frames_mapped))
    throw std::invalid_argument("frames lost and frame poses must fit the frames mapped");
  if (frames_weak < 0 || frames_relocalised < 0 ||
      static_cast<std::size_t>(frames_weak) + static_cast<std::size_t>(frames_relocalised) > frame_poses.size())
    throw std::invalid_argument("frames weak and relocalised must be counts of placed frames");
  const auto keyframe = [keyframes](int k) { return k >= 0 && k < static_cast<long long>(keyframes); };
  for (const FramePose& f : frame_poses)
    if (!keyframe(f.keyframe) || !isValidTransform(f.T_K_C) || !std::isfinite(f.timestamp))
      throw std::invalid_argument("frame " + std::to_string(f.frame_index) +
                                  ": its pose is not a rigid transform in a keyframe");
  if ((tracker.keyframe != -1 && !keyframe(tracker.keyframe)) || !isValidTransform(tracker.T_K_C) ||
      !isValidTransform(tracker.velocity) || tracker.frames_lost < 0)
    throw std::invalid_argument("the tracker's state does not fit the keyframes");
  for (const PoseGraphEdge& e : pose_graph_edges)
    if (!keyframe(e.from) || !keyframe(e.to) || e.from == e.to || !isValidTransform(e.T_from_to) ||
        !e.information.allFinite())
      throw std::invalid_argument("a pose-graph edge does not join two keyframes with a finite measurement");
  for (const LoopClosure& l : loops)
    if (!keyframe(l.from) || !keyframe(l.to)) throw std::invalid_argument("a loop closure names a missing keyframe");
}

Mapper::Mapper(const PinholeCamera& camera, const MapperParams& params, const TrackingParams& tracking)
    : camera_(camera), params_(params), tracking_(tracking), extractor_(params.features), integrator_(params.local_map),
      tracker_(tracking.tracker) {
  camera_.validate();
  params_.validate();
  // Fail on a bad cell size now rather than at the first keyframe.
  KeyframeContainer(camera_, params_.local_map.cell_size_px);
}

Mapper::Mapper(const PinholeCamera& camera, const MapperParams& params, KeyframeGraph graph, const MapperState& state,
               const TrackingParams& tracking)
    : Mapper(camera, params, tracking) {
  state.validate(graph.size());
  for (const Keyframe& k : graph.keyframes())
    if (k.container.cellSizePx() != params_.local_map.cell_size_px || !(k.container.camera() == camera_))
      throw std::invalid_argument("keyframe " + std::to_string(k.id) +
                                  ": its container does not use the mapper's camera and cell size");
  graph_ = std::move(graph);
  state_ = state;
  tracker_.restore(state_.tracker);
  pose_graph_.restore(std::move(state_.pose_graph_edges), std::move(state_.loops));
  state_.pose_graph_edges.clear();
  state_.loops.clear();
}

MapperState Mapper::state() const {
  MapperState out = state_;
  out.tracker = tracker_.state();
  out.pose_graph_edges.assign(pose_graph_.edges().begin(), pose_graph_.edges().end());
  out.loops = pose_graph_.loops();
  return out;
}

// Quality of a keyframe's resampled colour image: decodes within a few grey levels of the pixels.
constexpr int kResampledJpegQuality = 95;

int Mapper::newKeyframe(const RgbdFrame& frame, FrameFeatures features) {
  Keyframe k{0,
             frame.index,
             frame.timestamp,
             frame.T_W_C,
             frame.rgb_resampled ? CompressedImage(frame.rgb, kResampledJpegQuality)
                                 : CompressedImage(frame.rgb, frame.rgb_file),
             CompressedImage(frame.depth, frame.depth_file),
             std::move(features),
             KeyframeContainer(camera_, params_.local_map.cell_size_px),
             0,
             {}};
  return graph_.add(std::move(k)).id;
}

std::vector<StampedPose> Mapper::trajectory() const {
  std::vector<StampedPose> out;
  out.reserve(state_.frame_poses.size());
  for (const FramePose& f : state_.frame_poses)
    out.push_back({f.timestamp, graph_.keyframe(f.keyframe).T_W_K * f.T_K_C});
  return out;
}

std::optional<TrackingOutcome> Mapper::trackFrame(const TrackingFrame& observed, RgbdFrame* frame,
                                                  FrameReport* report) {
  // The first frame anchors the world frame at its given pose (the ground truth's when the
  // sequence has one, so maps and trajectories overlay it; else the identity).
  if (state_.current_keyframe < 0) return TrackingOutcome{};
  // After lost frames the prediction is stale: place recognition proposes keyframes whatever
  // their pose (the vocabulary's best scores; the views nearest the last pose before it is trained).
  std::vector<int> recognised;
  if (tracker_.framesLost() > 0) {
    const std::vector<KeyframeView> views = graph_.views();
    index_.sync(views);
    const PosePrefilter everywhere{.enabled = false};
    const Transform T_W_pred = *tracker_.predict(graph_);
    recognised = index_.ranked(*observed.features, T_W_pred, views, everywhere);
    if (recognised.empty()) recognised = index_.nearestViews(*observed.features, T_W_pred, views, everywhere);
  }
  TrackingOutcome outcome =
      tracker_.track(graph_, state_.current_keyframe, observed, camera_, params_.keyframes.prefilter, recognised);
  report->weak = outcome.weak;
  report->relocalised = outcome.relocalised;
  if (outcome.lost()) {
    tracker_.lose();
    ++state_.frames_lost;
    report->lost = true;
    return std::nullopt;
  }
  if (outcome.relocalised) ++state_.frames_relocalised;
  else if (outcome.weak) ++state_.frames_weak;
  frame->T_W_C = graph_.keyframe(outcome.keyframe).T_W_K * outcome.estimate.T_K_C;
  return outcome;
}

RelativePoseParams Mapper::loopEstimateParams() const {
  RelativePoseParams p = tracking_.tracker.relative;
  // The revisited keyframe sits where the drift put it: allow that much disagreement.
  p.max_jump_m = tracking_.loops.max_drift_m;
  p.max_jump_deg = tracking_.loops.max_drift_deg;
  p.pnp.search_radius_px = 0;  // and so far off that matches by projection would miss: brute force
  return p;
}

void Mapper::optimisePoseGraph(RgbdFrame* frame, int keyframe, const Transform& T_K_C, FrameReport* report) {
  const auto start = std::chrono::steady_clock::now();
  PoseGraphResult result;
  const double moved = pose_graph_.optimise(&graph_, tracking_.loops.graph, &result);
  report->ms.pose_graph_ms += msSince(start);
  frame->T_W_C = graph_.keyframe(keyframe).T_W_K * T_K_C;
  report->loop_closed = true;
  report->loop_correction_m = std::max(report->loop_correction_m, moved);
}

bool Mapper::closeLoop(int revisited, const TrackingFrame& observed, RgbdFrame* frame, FrameReport* report) {
  const Keyframe& R = graph_.keyframe(revisited);
  const RelativePose estimate =
      estimateRelativePose(R, observed, camera_, R.T_W_K.inverse() * frame->T_W_C, loopEstimateParams());
  if (estimate.status != RelativePose::Status::kGood || estimate.pnp_inliers < tracking_.loops.min_inliers)
    return false;
  // Edge R -> current from the frame: T_R_cur = T_R_C (measured) * T_C_cur (tracked). The
  // information of T_R_C moves into the current keyframe's frame.
  const Transform T_cur_C = graph_.keyframe(state_.current_keyframe).T_W_K.inverse() * frame->T_W_C;
  const Matrix6d info = informationInFrame(edgeInformation(estimate, tracking_.loops.edge_noise), T_cur_C.inverse());
  pose_graph_.add({revisited, state_.current_keyframe, estimate.T_K_C * T_cur_C.inverse(), info, true});
  optimisePoseGraph(frame, revisited, estimate.T_K_C, report);
  pose_graph_.recordLoop({frame->index, state_.current_keyframe, revisited, estimate.pnp_inliers,
                          report->loop_correction_m, report->ms.pose_graph_ms});
  return true;
}

Mapper::LoopEdge Mapper::addCovisibleEdges(int created, int previous, const TrackingOutcome& tracked,
                                           std::span<const std::pair<int, double>> covisible,
                                           const TrackingFrame& observed, const RgbdFrame& frame) {
  LoopEdge loop;
  for (const auto& [other, weight] : covisible) {
    if (other == tracked.keyframe) continue;
    // A keyframe the previous one is not linked to is a place seen again: a loop edge.
    const bool is_loop = other != previous && !graph_.edges().hasEdge(previous, other);
    if (is_loop && !tracking_.loops.enabled) continue;
    const Keyframe& K = graph_.keyframe(other);
    const RelativePose estimate = estimateRelativePose(K, observed, camera_, K.T_W_K.inverse() * frame.T_W_C,
                                                       is_loop ? loopEstimateParams() : tracking_.tracker.relative);
    if (estimate.status != RelativePose::Status::kGood ||
        (is_loop && estimate.pnp_inliers < tracking_.loops.min_inliers))
      continue;
    pose_graph_.add({other, created, estimate.T_K_C, edgeInformation(estimate, tracking_.loops.edge_noise), is_loop});
    if (is_loop && estimate.pnp_inliers > loop.inliers) loop.inliers = estimate.pnp_inliers, loop.to = other;
    loop.closed = loop.closed || is_loop;
  }
  return loop;
}

Mapper::LoopEdge Mapper::addLoopEdgeBeyondCovisibility(int created, int previous, const TrackingFrame& observed,
                                                       const RgbdFrame& frame) {
  // Drift may have moved the place seen again beyond the covisibility test's 8 px: candidates
  // are the keyframes the previous one is not linked to whose keypoints could project into
  // this frame at all (covisibilityBound, with a drift-sized margin), ranked by the share of
  // their features re-observed within that margin (delta at the margin; ties to the lower id),
  // the first few verified by a relative-pose estimate (descriptor matching, PnP, dense
  // refinement). Ranked by the bound, which saturates at 1 near a place seen again, the first few
  // were no better than the rest: on 7-Scenes they could not be verified while lower-ranked
  // keyframes could, and loops were missed (docs/notes/tracking.md, "Loop candidates").
  CovisibilityParams margin = params_.keyframes.covisibility;
  margin.max_reprojection_px = tracking_.loops.candidate_margin_px;
  const Keyframe& N = graph_.keyframe(created);
  std::vector<std::pair<double, int>> candidates;
  for (const Keyframe& K : graph_.keyframes()) {
    if (K.id == created || K.id == previous || graph_.edges().hasEdge(previous, K.id) ||
        graph_.edges().hasEdge(created, K.id) || !params_.keyframes.prefilter.accepts(K.T_W_K, frame.T_W_C) ||
        covisibilityBound(K.features, K.T_W_K, frame.T_W_C, camera_, margin) < params_.keyframes.tau)
      continue;
    candidates.emplace_back(-covisibility(K.features, K.T_W_K, N.features, N.T_W_K, camera_, margin), K.id);
  }
  std::sort(candidates.begin(), candidates.end());
  const std::size_t tried =
      std::min(candidates.size(), static_cast<std::size_t>(std::max(tracking_.loops.candidates, 0)));
  for (std::size_t i = 0; i < tried; ++i) {
    const int other = candidates[i].second;
    const Keyframe& K = graph_.keyframe(other);
    const RelativePose estimate =
        estimateRelativePose(K, observed, camera_, K.T_W_K.inverse() * frame.T_W_C, loopEstimateParams());
    if (estimate.status != RelativePose::Status::kGood || estimate.pnp_inliers < tracking_.loops.min_inliers) continue;
    pose_graph_.add({other, created, estimate.T_K_C, edgeInformation(estimate, tracking_.loops.edge_noise), true});
    return {true, other, estimate.pnp_inliers};
  }
  return {};
}

void Mapper::addKeyframeEdges(int created, int previous, const TrackingOutcome& tracked,
                              std::span<const std::pair<int, double>> covisible, const TrackingFrame& observed,
                              RgbdFrame* frame, FrameReport* report) {
  if (tracked.keyframe >= 0)
    pose_graph_.add({tracked.keyframe, created, tracked.estimate.T_K_C,
                     edgeInformation(tracked.estimate, tracking_.loops.edge_noise), false});
  LoopEdge loop = addCovisibleEdges(created, previous, tracked, covisible, observed, *frame);
  if (!loop.closed && tracking_.loops.enabled)
    loop = addLoopEdgeBeyondCovisibility(created, previous, observed, *frame);
  if (!loop.closed) return;
  optimisePoseGraph(frame, created, Transform::Identity(), report);
  // The covisibility edge of the loop, weighted by delta at the corrected poses.
  const Keyframe& N = graph_.keyframe(created);
  const Keyframe& L = graph_.keyframe(loop.to);
  graph_.edges().strengthen(
      created, loop.to,
      covisibility(L.features, L.T_W_K, N.features, N.T_W_K, camera_, params_.keyframes.covisibility));
  pose_graph_.recordLoop(
      {frame->index, previous, loop.to, loop.inliers, report->loop_correction_m, report->ms.pose_graph_ms});
}

std::function<void(RgbdFrame&)> Mapper::featuresAhead() const {
  auto extractor = std::make_shared<const FeatureExtractor>(params_.features);
  return [this, extractor](RgbdFrame& frame) {
    const auto start = std::chrono::steady_clock::now();
    frame.features =
        std::make_shared<const FrameFeatures>(extractor->extract(frame, camera_, params_.local_map.depth_range));
    frame.features_for = this;
    frame.features_ms = msSince(start);
  };
}

FrameFeatures Mapper::frameFeatures(const RgbdFrame& input, std::chrono::steady_clock::time_point start,
                                    FrameReport* report) {
  const bool features_ahead = input.features && input.features_for == this;
  FrameFeatures features =
      features_ahead ? *input.features : extractor_.extract(input, camera_, params_.local_map.depth_range);
  report->features = features.size();
  report->ms.features_ms = features_ahead ? input.features_ms : msSince(start);
  return features;
}

std::optional<TrackingOutcome> Mapper::placeFrame(const TrackingFrame& observed, DensePoints* points, RgbdFrame* frame,
                                                  FrameReport* report) {
  const auto track_start = std::chrono::steady_clock::now();
  *points = sampleDensePoints(*frame, camera_, params_.local_map.depth_range,
                              tracking_.tracker.relative.dense.strideFor(camera_));
  const std::optional<TrackingOutcome> outcome = trackFrame(observed, frame, report);
  report->ms.tracking_ms = msSince(track_start);
  return outcome;
}

FrameDecision Mapper::decideFrame(const FrameFeatures& features, const Transform& T_W_C,
                                  const std::vector<KeyframeView>& views) {
  const int current = state_.current_keyframe;
  if (params_.keyframe_every > 0) {
    const bool start_new = current < 0 || state_.frames_mapped % params_.keyframe_every == 0;
    FrameDecision decision;
    decision.kind = start_new ? FrameDecision::Kind::kNewKeyframe : FrameDecision::Kind::kUpdate;
    decision.keyframe = start_new ? -1 : current;
    return decision;
  }
  // The current keyframe first; only a frame that lost it asks the index for candidates
  // (the loop-closure search and, for a new keyframe, its edges).
  const std::span<const KeyframeView> current_view =
      current >= 0 ? std::span<const KeyframeView>(&views[current], 1) : std::span<const KeyframeView>();
  const FrameDecision decision = decideKeyframe(features, T_W_C, current, current_view, camera_, params_.keyframes);
  if (decision.kind == FrameDecision::Kind::kUpdate) return decision;
  index_.sync(views);
  const std::vector<KeyframeView> candidates =
      index_.candidates(features, T_W_C, views, params_.keyframes.prefilter, {current});
  return decideKeyframe(features, T_W_C, current, candidates, camera_, params_.keyframes);
}

void Mapper::revisitKeyframe(const TrackingFrame& observed, RgbdFrame* frame, FrameReport* report) {
  const int current = state_.current_keyframe;
  ++state_.revisits;
  report->keyframe = report->decision.keyframe;
  // A revisit of a keyframe the current one is not linked to closes a loop (tracked poses).
  if (tracksPoses() && tracking_.loops.enabled && current >= 0 && !graph_.edges().hasEdge(current, report->keyframe))
    closeLoop(report->keyframe, observed, frame, report);
  // The frame links the place it left to the place it recognised.
  if (current >= 0) graph_.edges().strengthen(current, report->keyframe, report->decision.delta_current);
}

void Mapper::startKeyframe(FrameFeatures features, const DensePoints& points, const TrackingOutcome& tracked,
                           const std::vector<KeyframeView>& views, RgbdFrame* frame, FrameReport* report) {
  const int current = state_.current_keyframe;
  const auto edges =
      params_.keyframe_every > 0
          ? std::vector<std::pair<int, double>>{}
          : edgesOfNewKeyframe(features, frame->T_W_C, current,
                               index_.candidates(features, frame->T_W_C, views, params_.keyframes.prefilter, {current},
                                                 index_.params().max_edge_candidates),
                               camera_, params_.keyframes);
  // The keyframe keeps the features (the estimates below only read them through `kept`).
  report->keyframe = newKeyframe(*frame, std::move(features));
  const FrameFeatures* kept = &graph_.keyframe(report->keyframe).features;
  for (const auto& [other, weight] : edges) graph_.edges().strengthen(report->keyframe, other, weight);
  if (params_.keyframe_every > 0 && current >= 0) graph_.edges().strengthen(report->keyframe, current, 0.0);
  if (tracksPoses() && current >= 0)
    addKeyframeEdges(report->keyframe, current, tracked, edges, {kept, &points, {}}, frame, report);
}

void Mapper::updateLocalMap(const RgbdFrame& frame, const TrackingOutcome& tracked, FrameReport* report) {
  Keyframe& keyframe = graph_.keyframe(state_.current_keyframe);
  // A frame placed on a weak estimate (the features or the local map alone) keeps its pose but
  // stays out of the local map it was placed against, unless it starts a keyframe: integrated, its
  // error became the map the next frames were aligned to: through a textureless stretch with no
  // PnP, the local map alone, fed by the frames it placed, carried them ever farther from the truth
  // (docs/notes/tracking.md, "Weak frames", has the Replica office0 figures).
  report->integrated = !tracksPoses() || !tracked.weak || tracked.relocalised ||
                       report->decision.kind == FrameDecision::Kind::kNewKeyframe;
  if (report->integrated) {
    integrator_.integrateFrame(frame, camera_, keyframe.T_W_K, &keyframe.container, &report->touched_cells);
    ++keyframe.frames_integrated;
    const Transform T_K_C = keyframe.T_W_K.inverse() * frame.T_W_C;
    if (addsFreeSpace(keyframe.frames_free, T_K_C))
      keyframe.frames_free.push_back(frameFreeSpace(frame, camera_, params_.local_map.depth_range, T_K_C));
  }
}

void Mapper::recordPose(const RgbdFrame& frame) {
  const Transform T_K_C = graph_.keyframe(state_.current_keyframe).T_W_K.inverse() * frame.T_W_C;
  state_.frame_poses.push_back({frame.index, frame.timestamp, state_.current_keyframe, T_K_C});
  if (tracksPoses()) tracker_.accept(graph_, state_.current_keyframe, T_K_C);
}

void Mapper::countFrame(const RgbdFrame& frame) {
  ++state_.frames_mapped;
  state_.last_frame_index = frame.index;
  state_.last_timestamp = frame.timestamp;
}

void Mapper::checkCanMap(const RgbdFrame& input) const {
  if (!canContinue())
    throw std::invalid_argument("the session does not store its current keyframe (vdmap session format 1 did not), "
                                "so mapping cannot continue from it; it can still be rendered, exported or opened");
  if (!isValidTransform(input.T_W_C))
    throw std::invalid_argument("frame " + std::to_string(input.index) + ": pose is not a finite rigid transform");
}

FrameReport Mapper::addFrame(const RgbdFrame& input) {
  checkCanMap(input);
  const auto start = std::chrono::steady_clock::now();
  FrameReport report;
  report.frame_index = input.index;
  FrameFeatures features = frameFeatures(input, start, &report);

  RgbdFrame frame = input;  // shares the images; only the pose may change
  DensePoints points;
  std::optional<PhotometricPoints> photometric;
  const TrackingFrame observed{&features, &points, [&]() -> const PhotometricPoints& {
                                 if (!photometric)
                                   photometric =
                                       samplePhotometricPoints(frame, camera_, params_.local_map.depth_range,
                                                               tracking_.tracker.relative.dense.strideFor(camera_));
                                 return *photometric;
                               }};
  TrackingOutcome tracked;
  if (tracksPoses()) {
    const std::optional<TrackingOutcome> outcome = placeFrame(observed, &points, &frame, &report);
    if (!outcome) {
      countFrame(input);
      report.ms.total_ms = msSince(start);
      return report;
    }
    tracked = *outcome;
  }

  const auto decide_start = std::chrono::steady_clock::now();
  const std::vector<KeyframeView> views = graph_.views();
  report.decision = decideFrame(features, frame.T_W_C, views);
  switch (report.decision.kind) {
    case FrameDecision::Kind::kUpdate: report.keyframe = report.decision.keyframe; break;
    case FrameDecision::Kind::kRevisit: revisitKeyframe(observed, &frame, &report); break;
    case FrameDecision::Kind::kNewKeyframe:
      startKeyframe(std::move(features), points, tracked, views, &frame, &report);
      break;
  }
  report.T_W_C = frame.T_W_C;
  // The keyframe left behind stops growing (unless revisited): its cells then hold what they
  // store, not the spare capacity their vector's doubling had reserved.
  if (state_.current_keyframe >= 0 && report.keyframe != state_.current_keyframe)
    graph_.keyframe(state_.current_keyframe).container.shrinkToFit();
  state_.current_keyframe = report.keyframe;
  report.ms.decision_ms = msSince(decide_start);

  const auto update_start = std::chrono::steady_clock::now();
  updateLocalMap(frame, tracked, &report);
  report.ms.update_ms = msSince(update_start);
  recordPose(frame);
  report.ms.total_ms = msSince(start);
  countFrame(frame);
  return report;
}

MapRefinementResult Mapper::refineKeyframePoses(const MapRefinementParams& params) {
  return vdmap::refineKeyframePoses(&graph_, &pose_graph_, tracking_.loops.graph, params);
}

}  // namespace vdmap
