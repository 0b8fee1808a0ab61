// The MappingWorker of a map file (mapping/files/map_file.h): one mapping snapshot and one global
// map, published at construction; nothing is ever rebuilt, since a map file has no local maps.
// Its thread only answers commands: each is refused with that reason, so waitIdle and the
// window's "busy" see them handled.
#include <algorithm>

#include "app/workbench/mapping_worker.h"
#include "app/workbench/workbench_state.h"
#include "mapping/io/camera_config.h"
#include "render/lod_order.h"

namespace vdmap::app::gui {

MappingWorker::MappingWorker(std::shared_ptr<const StaticMap> map) : static_map_(std::move(map)) {
  const StaticMap& m = *static_map_;
  sequence_folder_ = m.path.string();
  // Frames: those of the trajectory when the file has one (a map folder), else none.
  mapped_ = target_ = static_cast<int>(m.trajectory.size());

  auto snap = std::make_shared<MappingSnapshot>();
  snap->generation = ++mapping_generation_;
  snap->camera = cameraPreset(kStaticMapCamera);  // a map folder stores no intrinsics
  snap->frames_total = snap->frames_mapped = mapped_;
  std::vector<std::size_t> per_keyframe(m.keyframes.size(), 0);
  for (const Ellipsoid& e : m.ellipsoids)
    if (e.keyframe >= 0 && static_cast<std::size_t>(e.keyframe) < per_keyframe.size())
      ++per_keyframe[static_cast<std::size_t>(e.keyframe)];
  for (std::size_t id = 0; id < m.keyframes.size(); ++id) {
    KeyframeInfo k;
    k.id = static_cast<int>(id);
    k.T_W_K = m.keyframes[id].T_W_C;
    k.ellipsoids = per_keyframe[id];
    // Its place on the scrubber: the first trajectory entry at or after the keyframe's time.
    const auto at = std::lower_bound(m.trajectory.begin(), m.trajectory.end(), m.keyframes[id].t,
                                     [](const StampedPose& p, double t) { return p.t < t; });
    k.frame = static_cast<int>(at - m.trajectory.begin());
    snap->keyframes.push_back(std::move(k));
  }
  snap->current_keyframe = -1;
  snap->edges = m.edges;
  // The trajectory is held relative to keyframes: each frame to the newest keyframe at or before
  // its time (the first one for frames before it), so it is drawn where the file put it.
  // Without a trajectory, the keyframes stand for it (as for a session that stores no frame
  // poses), so the data up axis has cameras.
  if (!m.keyframes.empty()) {
    std::size_t k = 0;
    for (const StampedPose& p : m.trajectory) {
      while (k + 1 < m.keyframes.size() && m.keyframes[k + 1].t <= p.t) ++k;
      trajectory_.push_back({static_cast<int>(k), p.t, m.keyframes[k].T_W_C.inverse() * p.T_W_C, std::nullopt});
    }
    if (m.trajectory.empty())
      for (std::size_t id = 0; id < m.keyframes.size(); ++id)
        trajectory_.push_back({static_cast<int>(id), m.keyframes[id].t, Transform::Identity(), std::nullopt});
  }
  snap->trajectory = trajectory_.view();
  mapping_ = std::move(snap);

  auto global = std::make_shared<GlobalSnapshot>();
  global->map.ellipsoids = m.ellipsoids;
  global->map.sigma_e = global->map.merged = global->map.sigma_e_prime = m.ellipsoids.size();
  global->lod_order = render::lodOrder(global->map.ellipsoids);
  global->params = thresholds_;
  global->frames_mapped = mapped_;
  global->generation = ++generation_;
  global_ = std::move(global);

  worker_ = std::thread([this] { runStatic(); });
}

void MappingWorker::runStatic() {
  std::unique_lock lock(mutex_);
  while (!stop_) {
    const bool refused = !commands_.empty() || global_dirty_;
    bool news = refused;
    commands_.clear();
    global_dirty_ = false;
    playing_ = stop_at_keyframe_ = false;
    target_ = mapped_;
    if (refused) error_ = kStaticMapWhy;
    if (selection_dirty_) {
      // The selected keyframe, with no local map to show.
      auto snap = std::make_shared<SelectionSnapshot>();
      snap->serial = ++selection_serial_;
      snap->keyframe = selected_keyframe_;
      snap->generation = global_ ? global_->generation : 0;
      if (selected_keyframe_ >= 0 && static_cast<std::size_t>(selected_keyframe_) < static_map_->keyframes.size())
        snap->T_W_K = static_map_->keyframes[static_cast<std::size_t>(selected_keyframe_)].T_W_C;
      selection_ = std::move(snap);
      selection_dirty_ = false;
      news = true;
    }
    if (staticQueriesDue()) {
      // The point queries of a map file: its ellipsoids' gates and distances; with no keyframes
      // nothing is seen free (buildQueries notes it).
      const std::shared_ptr<const GlobalSnapshot> global = global_;
      queries_tried_ = global->generation;
      working_ = true;
      lock.unlock();
      buildQueries(KeyframeGraph{}, *global);
      lock.lock();
      working_ = false;
      continue;  // a command may have come meanwhile
    }
    idle_.notify_all();
    if (news && on_change_) on_change_();  // mutex_ held: read safely
    wake_.wait(lock);
  }
}

}  // namespace vdmap::app::gui
