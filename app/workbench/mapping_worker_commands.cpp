// The MappingWorker's thread-safe side: what the UI thread calls. Commands change the command
// state under the lock and wake the worker (mapping_worker.cpp runs them); the snapshots are read
// under the same lock.
#include "app/workbench/mapping_worker.h"
#include "mapping/core/message_text.h"

#include <algorithm>

namespace vdmap::app::gui {
namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

void MappingWorker::post(std::function<void()> command) {
  {
    std::lock_guard lock(mutex_);
    commands_.push_back(std::move(command));
    error_.clear();
  }
  wake_.notify_all();
}

void MappingWorker::update(const std::function<void()>& change) {
  {
    std::lock_guard lock(mutex_);
    error_.clear();
    change();
  }
  wake_.notify_all();
}

void MappingWorker::play() {
  update([this] {
    playing_ = true;
    target_ = framesTotal();
    next_frame_time_ = Clock::now();
  });
}

void MappingWorker::pause() {
  update([this] {
    playing_ = false;
    stop_at_keyframe_ = false;
    target_ = mapped_;
  });
}

void MappingWorker::setFps(float fps) {
  update([this, fps] { fps_ = std::max(0.f, fps); });
}

void MappingWorker::step() {
  update([this] {
    playing_ = false;
    target_ = std::min(std::max(target_, mapped_) + 1, framesTotal());  // taps add up before they are mapped
  });
}

void MappingWorker::stepToKeyframe() {
  update([this] {
    playing_ = false;
    stop_at_keyframe_ = true;
    target_ = framesTotal();
  });
}

void MappingWorker::seek(int frame) {
  if (!sequence_) return;
  frame = std::clamp(frame, std::max(0, base_frames_ - 1), framesTotal() - 1);
  bool restart = false;
  {
    std::lock_guard lock(mutex_);
    error_.clear();
    playing_ = false;
    stop_at_keyframe_ = false;
    restart = frame + 1 < mapped_;
    target_ = frame + 1;
  }
  if (restart) post([this] { restartMapper(); });
  wake_.notify_all();
}

void MappingWorker::setThresholds(const GlobalMapParams& thresholds) {
  thresholds.validate();
  {
    std::lock_guard lock(mutex_);
    thresholds_ = thresholds;
    global_dirty_ = true;
    last_edit_ = Clock::now();
  }
  wake_.notify_all();
}

void MappingWorker::rerun(const MapperParams& mapper) {
  if (!sequence_ || origin_) return;
  {
    std::lock_guard lock(mutex_);
    target_ = playing_ ? framesTotal() : std::max(target_, mapped_);
  }
  post([this, mapper] {
    mapper_params_ = mapper;
    restartMapper();
  });
}

void MappingWorker::setKeyframePose(int id, const Transform& T_W_K) {
  post([this, id, T_W_K] {
    ++pose_edits_;  // counted even when refused, so the UI does not wait for it
    try {
      mapper_->graph().setKeyframePose(id, T_W_K);
    } catch (...) {
      publishMapping();
      throw;
    }
    publishMapping();
    std::lock_guard lock(mutex_);
    global_dirty_ = true;
  });
}

void MappingWorker::loadTrajectory(const std::string& file) {
  post([this, file] {
    const TrajectoryMatch m = applyTrajectoryFile(mapper_->graph(), file);
    publishMapping();
    std::lock_guard lock(mutex_);
    global_dirty_ = true;
    message_ = file + ": " + counted(m.matched, "keyframe pose") + " replaced, " + std::to_string(m.untouched) +
               " kept, " + counted(m.unknown, "unmatched pose") + " ignored";
  });
}

void MappingWorker::withMapper(std::function<std::string(const Mapper&, const GlobalSnapshot&)> f) {
  post([this, f] {
    bool dirty = false;
    {
      std::lock_guard lock(mutex_);
      dirty = global_dirty_ || !global_;
    }
    if (dirty) rebuildGlobal();
    std::shared_ptr<const GlobalSnapshot> global_map = global();
    if (!global_map) throw std::runtime_error("there is no global map to export yet");
    // What is exported or saved is the map as it is, not the one before the last optimisation
    // that may be on screen.
    if (global_map->before_optimisation) global_map = buildGlobal(global_map->params, false);
    const std::string message = f(*mapper_, *global_map);
    std::lock_guard lock(mutex_);
    message_ = message;
  });
}

std::shared_ptr<const MappingSnapshot> MappingWorker::mapping() const {
  std::lock_guard lock(mutex_);
  return mapping_;
}

void MappingWorker::wantQueries(bool on) {
  {
    std::lock_guard lock(mutex_);
    if (queries_wanted_ == on) return;
    queries_wanted_ = on;
    if (!on) query_.reset(), queries_tried_ = -1;  // their memory back
    // A session's queries are built with the global map (the graph must be at the map's poses).
    else if (!static_map_) global_dirty_ = true;
  }
  wake_.notify_all();
}

void MappingWorker::wantMesh(bool on, const MeshParams& params) {
  params.validate();
  {
    std::lock_guard lock(mutex_);
    if (mesh_wanted_ == on && (!on || mesh_params_ == params)) return;
    mesh_wanted_ = on;
    mesh_params_ = params;
    if (on && !static_map_) global_dirty_ = true;  // the mesh comes with the next map
  }
  wake_.notify_all();
}

std::shared_ptr<const QuerySnapshot> MappingWorker::query() const {
  std::lock_guard lock(mutex_);
  return query_;
}

std::shared_ptr<const GlobalSnapshot> MappingWorker::global() const {
  std::lock_guard lock(mutex_);
  return global_;
}

template <class T>
void MappingWorker::setAndWake(T* field, T value, bool* dirty) {
  {
    std::lock_guard lock(mutex_);
    if (*field == value) return;
    *field = value;
    *dirty = true;
  }
  wake_.notify_all();
}

void MappingWorker::showBeforeOptimisation(bool before) { setAndWake(&before_optimisation_, before, &global_dirty_); }

void MappingWorker::selectKeyframe(int id) { setAndWake(&selected_keyframe_, id, &selection_dirty_); }

std::shared_ptr<const SelectionSnapshot> MappingWorker::selection() const {
  std::lock_guard lock(mutex_);
  return selection_;
}

PlayerStatus MappingWorker::status() const {
  std::lock_guard lock(mutex_);
  return {playing_, workLeft(), target_, error_, message_, fps_};
}

void MappingWorker::setOnChange(std::function<void()> on_change) {
  std::lock_guard lock(mutex_);  // the worker reads it after taking the lock once
  on_change_ = std::move(on_change);
}

void MappingWorker::waitIdle() {
  std::unique_lock lock(mutex_);
  idle_.wait(lock, [this] { return !workLeft() || stop_; });
}

}  // namespace vdmap::app::gui
