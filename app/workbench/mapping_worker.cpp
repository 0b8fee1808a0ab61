#include "app/workbench/mapping_worker.h"

#include <algorithm>

#include "app/cli/error_text.h"
#include "app/cli/release_memory.h"
#include "mapping/core/timing.h"
#include "mapping/local_map/ellipsoid_filter.h"
#include "render/lod_order.h"
#include "render/map_scene.h"

namespace vdmap::app::gui {
namespace {
using Clock = std::chrono::steady_clock;

std::vector<Transform> snapshotPoses(const KeyframeGraph& graph) {
  std::vector<Transform> poses;
  poses.reserve(graph.size());
  for (const Keyframe& k : graph.keyframes()) poses.push_back(k.T_W_K);
  return poses;
}
}  // namespace

std::vector<Transform> MappingSnapshot::keyframePoses(bool before_optimisation) const {
  if (before_optimisation && !keyframes_before.empty()) return keyframes_before;
  std::vector<Transform> out;
  out.reserve(keyframes.size());
  for (const KeyframeInfo& k : keyframes) out.push_back(k.T_W_K);
  return out;
}

Transform MappingSnapshot::framePose(std::size_t i, bool before_optimisation) const {
  const TrajectoryPoint& f = trajectory[i];
  const auto k = static_cast<std::size_t>(f.keyframe);
  const bool before = before_optimisation && k < keyframes_before.size();
  return (before ? keyframes_before[k] : keyframes[k].T_W_K) * f.T_K_C;
}

std::vector<Transform> MappingSnapshot::trajectoryWorld(bool before_optimisation) const {
  std::vector<Transform> out;
  out.reserve(trajectory.size());
  for (std::size_t i = 0; i < trajectory.size(); ++i) out.push_back(framePose(i, before_optimisation));
  return out;
}

std::vector<Transform> MappingSnapshot::groundTruthWorld() const {
  std::vector<Transform> out;
  for (const TrajectoryPoint& f : trajectory)
    if (f.T_W_C_truth) out.push_back(*f.T_W_C_truth);
  return out;
}

bool MappingSnapshot::hasGroundTruth() const {
  return std::any_of(trajectory.begin(), trajectory.end(),
                     [](const TrajectoryPoint& f) { return f.T_W_C_truth.has_value(); });
}

MappingWorker::MappingWorker(Sequence sequence, const MapperParams& mapper, const GlobalMapParams& thresholds,
                             std::optional<MapRefinementParams> refine)
    : sequence_(std::move(sequence)), sequence_folder_(sequence_->folder().string()), mapper_params_(mapper),
      refine_(std::move(refine)), thresholds_(thresholds) {
  thresholds_.validate();
  mapper_ = std::make_unique<Mapper>(sequence_->camera(), mapper_params_);
  start();
}

MappingWorker::MappingWorker(Session saved, const GlobalMapParams& thresholds, std::optional<Sequence> rest,
                             std::optional<MapRefinementParams> refine, std::vector<FrameEntry> truth)
    : sequence_(std::move(rest)), sequence_folder_(saved.info.sequence), mapper_params_(saved.info.mapper),
      refine_(std::move(refine)), thresholds_(thresholds) {
  for (FrameEntry& e : truth)
    if (e.has_pose) session_truth_.push_back(std::move(e));
  std::sort(session_truth_.begin(), session_truth_.end(),
            [](const FrameEntry& a, const FrameEntry& b) { return a.t_depth < b.t_depth; });
  thresholds_.validate();
  base_frames_ = saved.info.state.frames_mapped;
  if (sequence_) origin_ = std::make_shared<const Session>(saved);  // kept to seek back to
  mapper_ = std::make_unique<Mapper>(saved.info.camera, mapper_params_, std::move(saved.graph), saved.info.state);
  mapped_ = target_ = base_frames_;
  trajectoryOfSession();
  global_dirty_ = true;
  start();
}

void MappingWorker::trajectoryOfSession() {
  // A session mapped with ground-truth poses had one for every frame it mapped.
  frames_with_groundtruth_ = mapper_params_.poses == PoseSource::kGroundTruth ? base_frames_ : 0;
  // Sessions since format 4 store every mapped frame's pose; older ones only the keyframes'.
  if (!mapper_->framePoses().empty()) {
    for (const vdmap::FramePose& f : mapper_->framePoses()) {
      TrajectoryPoint pose{f.keyframe, f.timestamp, f.T_K_C, std::nullopt};
      // Tracked poses: the sequence's ground truth of the same frame (its depth timestamp).
      const auto it = std::lower_bound(session_truth_.begin(), session_truth_.end(), f.timestamp - 1e-6,
                                       [](const FrameEntry& e, double t) { return e.t_depth < t; });
      if (it != session_truth_.end() && std::abs(it->t_depth - f.timestamp) <= 1e-6) {
        pose.T_W_C_truth = it->T_W_C;
        ++frames_with_groundtruth_;
      }
      trajectory_.push_back(pose);
    }
    return;
  }
  for (const Keyframe& k : mapper_->graph().keyframes())
    trajectory_.push_back({k.id, k.timestamp, Transform::Identity(), std::nullopt});
}

void MappingWorker::start() {
  publishMapping();
  worker_ = std::thread([this] { run(); });
}

MappingWorker::~MappingWorker() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  worker_.join();
}

bool MappingWorker::workLeft() const {
  return working_ || !commands_.empty() || selection_dirty_ || mapped_ < target_ || global_dirty_ || staticQueriesDue();
}

void MappingWorker::run() {
  std::unique_lock lock(mutex_);
  while (!stop_) {
    std::function<void()> job;
    if (!commands_.empty()) {
      job = std::move(commands_.front());
      commands_.pop_front();
    } else if (selection_dirty_) {
      job = [this] { publishSelection(); };
    } else if (mapped_ < target_) {
      if (playing_ && fps_ > 0.f && Clock::now() < next_frame_time_) {
        wake_.wait_until(lock, next_frame_time_);
        continue;
      }
      next_frame_time_ = std::max(next_frame_time_, Clock::now()) +
                         std::chrono::microseconds(fps_ > 0.f ? static_cast<long>(1e6 / fps_) : 0);
      // While mapping, rebuild the global map only now and then, so that map building takes at
      // most ~1/5 of the worker's time and the map on screen still grows.
      const bool rebuild = global_dirty_ && secondsSince(last_build_) > std::max(1.0, 4 * last_build_s_);
      job = [this, rebuild] { rebuild ? rebuildGlobal() : mapOneFrame(); };
    } else if (global_dirty_) {
      job = [this] { rebuildGlobal(); };
    } else {
      playing_ = false;
      idle_.notify_all();
      if (on_change_) on_change_();  // mutex_ held: read safely
      wake_.wait(lock);
      continue;
    }
    working_ = true;
    lock.unlock();
    try {
      job();
    } catch (const std::exception& e) {
      std::lock_guard relock(mutex_);
      error_ = errorMessage(e);
    }
    lock.lock();
    working_ = false;
  }
}

void MappingWorker::publishMapping() {
  auto snap = std::make_shared<MappingSnapshot>();
  snap->generation = ++mapping_generation_;
  snap->camera = mapper_->camera();
  snap->mapper = mapper_params_;
  snap->pose_edits = pose_edits_;
  {
    std::lock_guard lock(mutex_);
    snap->frames_total = framesTotal();
  }
  snap->frames_mapped = sequence_ ? mapper_->framesMapped() : snap->frames_total;
  snap->current_keyframe = mapper_->currentKeyframe();
  snap->rgb = last_rgb_;
  snap->depth = last_depth_;
  snap->times = times_.view();
  snap->trajectory = trajectory_.view();
  for (const Keyframe& k : mapper_->graph().keyframes())
    snap->keyframes.push_back(
        {k.id, positionOf(k.frame_index), k.T_W_K, k.rgb_image, k.container.size(), k.frames_integrated});
  snap->edges = mapper_->graph().edges().edges();
  snap->frames_with_groundtruth = frames_with_groundtruth_;
  snap->frames_lost = mapper_->framesLost();
  snap->frames_weak = mapper_->framesWeak();
  snap->frames_relocalised = mapper_->framesRelocalised();
  for (const LoopClosure& loop : mapper_->poseGraph().loops())
    snap->loops.push_back({loop, positionOf(loop.frame_index)});
  snap->keyframes_before = posesBeforeOptimisation();
  // The final refinement comes after every loop closure (it runs after the sequence's last frame).
  if (!snap->keyframes_before.empty()) {
    if (refinement_.kind == LastOptimisation::Kind::kRefinement) snap->last_optimisation = refinement_;
    else if (!snap->loops.empty())
      snap->last_optimisation = {LastOptimisation::Kind::kLoop, static_cast<int>(snap->loops.size()) - 1, "", 0, 0};
  }
  {
    std::lock_guard lock(mutex_);
    mapping_ = std::move(snap);
  }
  notifyChange();
}

void MappingWorker::mapOneFrame() {
  const int i = mapper_->framesMapped();
  try {
    const RgbdFrame frame = sequence_->load(static_cast<std::size_t>(i - base_frames_));
    const FrameReport report = mapper_->addFrame(frame);
    times_.push_back(report.ms);
    if (!report.lost) {  // a frame the tracker could not place has no pose
      const vdmap::FramePose& placed = mapper_->framePoses().back();
      TrajectoryPoint pose{placed.keyframe, placed.timestamp, placed.T_K_C, std::nullopt};
      const FrameEntry& entry = sequence_->entries()[static_cast<std::size_t>(i - base_frames_)];
      if (mapper_params_.poses == PoseSource::kTrack && entry.has_pose) pose.T_W_C_truth = entry.T_W_C;
      trajectory_.push_back(pose);
    }
    if (sequence_->entries()[static_cast<std::size_t>(i - base_frames_)].has_pose) ++frames_with_groundtruth_;
    // After the sequence's last frame, tracked keyframe poses are refined from the settled local
    // maps as `vdmap map` does (B shows the map before it); frames follow their keyframes.
    std::string refined;
    if (mapper_params_.poses == PoseSource::kTrack && refine_ && i + 1 == framesTotal()) {
      const MapRefinementResult r = mapper_->refineKeyframePoses(*refine_);
      const char* method = refine_->method == MapRefinementMethod::kJoint ? "joint" : "pairwise";
      char text[200] = "";
      if (r.refused)
        std::snprintf(text, sizeof text,
                      "keyframe poses kept as tracked: the joint refinement of %d local-map pairs ran "
                      "too far (%.1f s)",
                      r.pairs, 1e-3 * r.ms);
      else if (r.rounds > 0)
        std::snprintf(text, sizeof text,
                      "keyframe poses refined (%s) from %d of %d covisible pairs' local maps (%.1f mm "
                      "at most, %.1f s)",
                      method, r.edges, r.pairs, 1e3 * r.moved_m, 1e-3 * r.ms);
      refined = text;
      if (!r.refused && r.rounds > 0)
        refinement_ = {LastOptimisation::Kind::kRefinement, -1, method, r.pairs, r.moved_m};
    }
    last_rgb_ = frame.rgb;
    last_depth_ = frame.depth;
    publishMapping();
    std::lock_guard lock(mutex_);
    mapped_ = i + 1;
    global_dirty_ = true;
    if (!refined.empty()) message_ = refined;
    if (stop_at_keyframe_ && report.decision.kind == FrameDecision::Kind::kNewKeyframe) {
      stop_at_keyframe_ = false;
      target_ = mapped_;
    }
  } catch (const std::exception& e) {
    std::lock_guard lock(mutex_);
    error_ = "frame " + std::to_string(i) + ": " + errorMessage(e);
    target_ = mapped_;
    playing_ = false;
  }
}

std::vector<Transform> MappingWorker::posesBeforeOptimisation() const {
  const KeyframeGraph& graph = mapper_->graph();
  const std::vector<Transform>& before = mapper_->poseGraph().posesBeforeOptimisation();
  const std::size_t n = std::min(before.size(), graph.size());
  if (n == 0) return {};
  std::vector<Transform> out(before.begin(), before.begin() + static_cast<std::ptrdiff_t>(n));
  const Transform correction = before[n - 1] * graph.keyframe(static_cast<int>(n - 1)).T_W_K.inverse();
  for (std::size_t id = n; id < graph.size(); ++id)
    out.push_back(correction * graph.keyframe(static_cast<int>(id)).T_W_K);
  return out;
}

int MappingWorker::positionOf(int frame_index) const {
  if (!sequence_) return frame_index;
  const std::vector<FrameEntry>& entries = sequence_->entries();
  const auto it = std::lower_bound(entries.begin(), entries.end(), frame_index,
                                   [](const FrameEntry& e, int index) { return e.index < index; });
  if (it == entries.end() || it->index != frame_index) return frame_index;  // a saved session's own frame
  return base_frames_ + static_cast<int>(it - entries.begin());
}

std::shared_ptr<GlobalSnapshot> MappingWorker::buildGlobal(
    const GlobalMapParams& params, bool before_optimisation,
    const std::function<void(const KeyframeGraph&, const std::shared_ptr<GlobalSnapshot>&)>& with_graph) {
  auto snap = std::make_shared<GlobalSnapshot>();
  snap->params = params;
  const std::vector<Transform> before = before_optimisation ? posesBeforeOptimisation() : std::vector<Transform>();
  if (before.empty()) {
    snap->map = buildGlobalMap(mapper_->graph(), params, &global_workspace_);
    if (with_graph) with_graph(mapper_->graph(), snap);
    return snap;
  }
  // The local maps live in their keyframes' frames and do not change: the graph's poses are
  // swapped for the build and put back (the worker owns the mapper; nothing else reads it now).
  KeyframeGraph& graph = mapper_->graph();
  const std::vector<Transform> now = snapshotPoses(graph);
  struct Restore {
    KeyframeGraph& graph;
    const std::vector<Transform>& poses;
    ~Restore() {
      for (std::size_t id = 0; id < poses.size(); ++id) graph.setKeyframePose(static_cast<int>(id), poses[id]);
    }
  } restore{graph, now};
  for (std::size_t id = 0; id < before.size(); ++id) graph.setKeyframePose(static_cast<int>(id), before[id]);
  snap->map = buildGlobalMap(graph, params, &global_workspace_);
  snap->before_optimisation = true;
  if (with_graph) with_graph(graph, snap);
  return snap;
}

void MappingWorker::rebuildGlobal() {
  GlobalMapParams params;
  bool before = false, queries = false, mesh = false;
  MeshParams mesh_params;
  Clock::time_point t_edit;
  {
    std::lock_guard lock(mutex_);
    params = thresholds_;
    before = before_optimisation_;
    queries = queries_wanted_;
    mesh = mesh_wanted_;
    mesh_params = mesh_params_;
    global_dirty_ = false;
    t_edit = last_edit_;
  }
  const auto t0 = Clock::now();
  // The map is published as soon as it is built; the point queries follow it, built with the
  // graph at the poses the map was built with (so they answer at corrected poses).
  const auto publish = [&](const KeyframeGraph& graph, const std::shared_ptr<GlobalSnapshot>& snap) {
    snap->t_edit = t_edit;
    snap->t_build_start = t0;
    snap->lod_order = render::lodOrder(snap->map.ellipsoids);
    if (mesh) buildMesh(graph, mesh_params, *snap);
    snap->t_build_end = Clock::now();
    releaseFreedMemory();  // the build's other temporaries, before the next frames
    {
      std::lock_guard lock(mutex_);
      snap->frames_mapped = mapped_;
      snap->generation = ++generation_;
      snap->t_published = Clock::now();
      global_ = snap;
      selection_dirty_ = true;
      last_build_ = Clock::now();
      last_build_s_ = secondsSince(t0);
    }
    notifyChange();
    if (queries) buildQueries(graph, *snap);
  };
  try {
    buildGlobal(params, before, publish);
  } catch (const std::exception& e) {
    std::lock_guard lock(mutex_);
    error_ = std::string("global map: ") + errorMessage(e);
    return;
  }
  std::lock_guard lock(mutex_);
  last_build_s_ = secondsSince(t0);  // the queries' build counts in the worker's share of map building
}

void MappingWorker::buildMesh(const KeyframeGraph& graph, const MeshParams& params, GlobalSnapshot& snap) {
  const auto t0 = Clock::now();
  try {
    snap.mesh = std::make_shared<const render::ColoredMesh>(
        render::toColoredMesh(buildSurfaceMesh(graph, snap.map, params, snap.params)));
  } catch (const std::exception& e) {  // too large (max_triangles): the map is published without it
    std::lock_guard lock(mutex_);
    error_ = std::string("surface mesh: ") + errorMessage(e);
  }
  snap.mesh_ms = 1e3 * secondsSince(t0);
}

void MappingWorker::buildQueries(const KeyframeGraph& graph, const GlobalSnapshot& snap) {
  auto query = std::make_shared<QuerySnapshot>();
  query->generation = snap.generation;
  const auto t0 = Clock::now();
  try {
    query->map = std::make_shared<const QueryMap>(QueryMap::build(graph, snap.map, QueryParams{}));
  } catch (const std::exception& e) {
    std::lock_guard lock(mutex_);
    error_ = std::string("point queries: ") + errorMessage(e);
    return;
  }
  query->build_ms = 1e3 * secondsSince(t0);
  if (graph.size() == 0) query->note = "no keyframes: free space unknown";
  {
    std::lock_guard lock(mutex_);
    query_ = std::move(query);
  }
  notifyChange();
}

void MappingWorker::publishSelection() {
  auto snap = std::make_shared<SelectionSnapshot>();
  snap->serial = ++selection_serial_;
  std::shared_ptr<const GlobalSnapshot> global;
  {
    std::lock_guard lock(mutex_);
    snap->keyframe = selected_keyframe_;
    selection_dirty_ = false;
    global = global_;
  }
  snap->generation = global ? global->generation : 0;
  const KeyframeGraph& graph = mapper_->graph();
  if (global && snap->keyframe >= 0 && snap->keyframe < static_cast<int>(graph.size())) {
    // Filtered again rather than read from global->map.kept: the container may have grown since
    // the build, and one keyframe's filter costs little. At the pose the global map was built with.
    const Keyframe& k = graph.keyframe(snap->keyframe);
    const auto id = static_cast<std::size_t>(k.id);
    const std::vector<Transform> before =
        global->before_optimisation ? posesBeforeOptimisation() : std::vector<Transform>();
    snap->T_W_K = id < before.size() ? before[id] : k.T_W_K;
    snap->local = keptEllipsoids(k.container, global->params.filter, snap->T_W_K, k.id);
  }
  {
    std::lock_guard lock(mutex_);
    selection_ = std::move(snap);
  }
  notifyChange();
}

void MappingWorker::restartMapper() {
  refinement_ = {};
  times_.clear();
  trajectory_.clear();
  if (origin_) {  // back to the saved session, whose frames are not in the sequence
    mapper_ = std::make_unique<Mapper>(origin_->info.camera, mapper_params_, origin_->graph, origin_->info.state);
    trajectoryOfSession();
  } else {
    mapper_ = std::make_unique<Mapper>(sequence_->camera(), mapper_params_);
    frames_with_groundtruth_ = 0;
  }
  last_rgb_ = cv::Mat();
  last_depth_ = cv::Mat();
  publishMapping();
  std::lock_guard lock(mutex_);
  mapped_ = base_frames_;
  global_dirty_ = true;
}

void MappingWorker::notifyChange() const {
  std::function<void()> on_change;
  {
    std::lock_guard lock(mutex_);
    on_change = on_change_;
  }
  if (on_change) on_change();
}

}  // namespace vdmap::app::gui
