#pragma once
// The workbench's model: one sequence, its Mapper and the global map, owned by a worker thread.
// The UI thread sends commands through the thread-safe methods below and reads immutable
// snapshots; it never touches the Mapper. One mutex guards the command state and the snapshot
// pointers (no other lock, so no lock order to keep); mapping and map building run unlocked.
// What only the inspector needs (one keyframe's local map) is computed by the worker for the
// selected keyframe alone and published apart, so a selection change copies no global map.
// The worker's thread lives in mapping_worker.cpp, the UI thread's side in mapping_worker_commands.cpp.
#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "app/workbench/append_log.h"
#include "mapping/files/map_file.h"
#include "mapping/files/session_file.h"
#include "mapping/global_map/global_map.h"
#include "mapping/mesh/surface_mesh.h"
#include "mapping/pipeline/mapper.h"
#include "mapping/query/query_map.h"
#include "mapping/sequence/sequence.h"
#include "render/scene_types.h"

namespace vdmap::app::gui {

/// One keyframe as the UI sees it.
struct KeyframeInfo {
  int id = 0;
  int frame = 0;  ///< position in the sequence (on the scrubber, after --frames) of the frame that created it
  Transform T_W_K = Transform::Identity();
  CompressedImage rgb;         ///< shared with the keyframe; decode() when shown
  std::size_t ellipsoids = 0;  ///< stored in its container
  int frames_integrated = 0;
};

/// Where one mapped frame was: relative to the keyframe it went into, so that the trajectory
/// follows a keyframe's pose when it is corrected.
struct TrajectoryPoint {
  int keyframe = 0;
  double t = 0;  ///< the frame's timestamp (s, the sequence's depth time; FramePose::timestamp)
  Transform T_K_C = Transform::Identity();
  /// With tracked poses (PoseSource::kTrack): the sequence's ground-truth T_W_C of the frame,
  /// when it has one (the tracker anchors the world frame at the first frame's, so the two
  /// trajectories share a frame and are drawn as they are, unaligned).
  std::optional<Transform> T_W_C_truth;
};

/// One loop closure (Mapper::poseGraph().loops()) as the scrubber shows it.
struct LoopEvent {
  LoopClosure loop;
  int position = 0;  ///< the closing frame on the scrubber (0-based, counted like frames_mapped)
};

/// The last pose-graph optimisation of the keyframe poses, the one "before optimisation" (B)
/// undoes: a loop closure, or the refinement after the sequence's last frame (tracked poses).
struct LastOptimisation {
  enum class Kind { kNone, kLoop, kRefinement };
  Kind kind = Kind::kNone;
  int loop = -1;  ///< kLoop: its index in MappingSnapshot::loops
  /// kRefinement: "joint" or "pairwise", the covisible pairs registered (MapRefinementResult::pairs)
  /// and the largest keyframe move (m, MapRefinementResult::moved_m).
  std::string method;
  int pairs = 0;
  double correction_m = 0;
};

/// The mapping state after the last mapped frame (replaced after every frame).
struct MappingSnapshot {
  int generation = 0;  ///< 1, 2, ... per snapshot published by this session
  PinholeCamera camera;
  MapperParams mapper;  ///< the parameters the keyframes were mapped with
  int frames_total = 0;
  int frames_mapped = 0;  ///< frames [0, frames_mapped) of the sequence are in the map
  int current_keyframe = -1;
  cv::Mat rgb, depth;            ///< the last mapped frame (RGB order / raw 16-bit depth)
  SharedSpan<StageTimes> times;  ///< per mapped frame
  std::vector<KeyframeInfo> keyframes;
  std::vector<CovisibilityEdge> edges;
  SharedSpan<TrajectoryPoint> trajectory;  ///< per mapped frame that was placed (lost ones have none)
  int pose_edits = 0;                      ///< setKeyframePose calls handled so far (applied or refused)
  /// Mapped frames the sequence has a ground-truth pose for, whatever the poses were mapped with
  /// (mapper.poses: with ground-truth poses every mapped frame had one).
  int frames_with_groundtruth = 0;
  int frames_lost = 0;           ///< frames the tracker could not place (skipped, not integrated)
  int frames_weak = 0;           ///< placed on the current keyframe's weak estimate (Mapper::framesWeak)
  int frames_relocalised = 0;    ///< placed against another keyframe after a weak estimate
  std::vector<LoopEvent> loops;  ///< loop closures so far, oldest first
  /// T_W_K of every keyframe as it was before the last pose-graph optimisation; empty when there
  /// was none. Keyframes made after it are moved by the correction of the newest keyframe that
  /// existed then (they were tracked from the corrected poses), so the map and trajectory keep
  /// their shape behind it.
  std::vector<Transform> keyframes_before;
  /// What keyframes_before is before: kNone when it is empty.
  LastOptimisation last_optimisation;

  /// Keyframe poses by id: the current ones, or those before the last optimisation (when there
  /// was one).
  std::vector<Transform> keyframePoses(bool before_optimisation = false) const;
  /// T_W_C of trajectory entry i under the keyframe poses of this snapshot (or those before the
  /// last optimisation).
  Transform framePose(std::size_t i, bool before_optimisation = false) const;
  /// framePose of every trajectory entry.
  std::vector<Transform> trajectoryWorld(bool before_optimisation = false) const;
  /// The ground-truth T_W_C of the entries that have one (tracked poses only; else empty).
  std::vector<Transform> groundTruthWorld() const;
  /// Whether a ground-truth trajectory is drawn beside the tracked one (tracked poses only: with
  /// ground-truth poses the two coincide). Whether the sequence has ground truth at all is
  /// frames_with_groundtruth.
  bool hasGroundTruth() const;
};

/// One global map build (replaced after every rebuild).
struct GlobalSnapshot {
  GlobalMap map;
  GlobalMapParams params;
  int frames_mapped = 0;  ///< the mapping state it was built from
  int generation = 0;     ///< 1, 2, ... per build
  /// render::lodOrder of map.ellipsoids: the 3-D view's fast-pass order, computed by the worker
  /// so that a new map costs the UI thread no sort (0.13 s at 1M ellipsoids).
  std::vector<std::uint32_t> lod_order;
  /// The surface mesh (docs/method.md 14) of the same local maps, poses and kept cells, while the
  /// mesh layer is wanted (MappingWorker::wantMesh): built with the map, before it is published,
  /// so the two arrive together. Null when not wanted (or when it failed: status().error says why).
  std::shared_ptr<const render::ColoredMesh> mesh;
  double mesh_ms = 0;  ///< buildSurfaceMesh's time
  /// Built with the keyframe poses before the last pose-graph optimisation
  /// (MappingWorker::showBeforeOptimisation).
  bool before_optimisation = false;
  /// Latency stages (steady clock): the newest threshold edit it includes (setThresholds; the
  /// epoch before the first), when its build started and ended, and when it was published to the
  /// UI. The scripted latency measurement adds the first frame that draws it (script_run.cpp).
  std::chrono::steady_clock::time_point t_edit{}, t_build_start{}, t_build_end{}, t_published{};
};

/// The point queries (docs/method.md 13) of one global map build: built by the worker right after
/// the map while queries are wanted (MappingWorker::wantQueries), and published just after it, so
/// a pose edit, loop closure or threshold change answers at the corrected poses.
struct QuerySnapshot {
  int generation = 0;                   ///< the GlobalSnapshot's it was built with
  std::shared_ptr<const QueryMap> map;  ///< never null
  double build_ms = 0;                  ///< QueryMap::build's time
  /// Why some answers are missing ("" when none): a map file has no keyframes, so no free space.
  std::string note;
};

/// The selected keyframe's local map (replaced after a selection change and after every rebuild).
struct SelectionSnapshot {
  int serial = 0;      ///< 1, 2, ... per selection published by this session
  int keyframe = -1;   ///< -1: none selected
  int generation = 0;  ///< the GlobalSnapshot whose thresholds filtered it (0: none built yet)
  /// The keyframe's ellipsoids kept by those thresholds, world frame, container order; empty while
  /// the keyframe does not exist (yet).
  std::vector<Ellipsoid> local;
  /// The keyframe pose `local` was moved to the world with: the global map's (its pose before the
  /// last optimisation when that map shows it).
  Transform T_W_K = Transform::Identity();
};

/// Playback state as the UI shows it.
struct PlayerStatus {
  bool playing = false;
  bool busy = false;    ///< mapping, re-running or rebuilding the global map
  int target = 0;       ///< frames the worker maps up to
  std::string error;    ///< the last failure (a bad frame, a pose file), empty when none
  std::string message;  ///< the last command's outcome, e.g. "12 keyframe poses replaced"
  float fps = 0.f;      ///< the playback limit (setFps) in frames per second; 0: none
};

class MappingWorker {
 public:
  /// Starts the worker (paused, nothing mapped). Throws std::invalid_argument for bad params.
  /// With tracked poses, `refine` (nullopt: none) refines the keyframe poses after the last frame
  /// as `vdmap map --refine` does.
  MappingWorker(Sequence sequence, const MapperParams& mapper, const GlobalMapParams& thresholds,
                std::optional<MapRefinementParams> refine = MapRefinementParams{});
  /// A saved session (.vdmap): its keyframes are there; thresholds and poses are live as usual.
  /// With `rest`, the frames of its sequence after the session's last one, the player continues
  /// mapping from the session's state (seeking back to before the session's end restores it);
  /// without, the player commands and seek do nothing. Re-run does nothing either way.
  /// `truth`: for a session mapped with tracked poses, its sequence's frames (their ground-truth
  /// poses, matched to the session's frames by timestamp) when the folder has them, so the
  /// tracking error and the ground-truth line show as they did while it was mapped.
  MappingWorker(Session saved, const GlobalMapParams& thresholds, std::optional<Sequence> rest = std::nullopt,
                std::optional<MapRefinementParams> refine = MapRefinementParams{}, std::vector<FrameEntry> truth = {});
  // --- Static maps (mapping_worker_static.cpp) ---
  /// A map file read whole (loadStaticMap): publishes one mapping snapshot (its keyframe poses,
  /// edges and trajectory) and one global snapshot, and nothing after. The player, thresholds,
  /// re-run, pose edits and selections change nothing (the error says a map file has no local
  /// maps to rebuild from); withMapper is refused the same way.
  explicit MappingWorker(std::shared_ptr<const StaticMap> map);
  /// The map file this worker shows (null for a sequence or session).
  const StaticMap* staticMap() const { return static_map_.get(); }
  // --- end static maps ---
  ~MappingWorker();
  MappingWorker(const MappingWorker&) = delete;
  MappingWorker& operator=(const MappingWorker&) = delete;

  /// Null for a saved session without its sequence; for one with, the frames after the session's.
  const Sequence* sequence() const { return sequence_ ? &*sequence_ : nullptr; }
  /// The folder the map's frames come from (a saved session's as stored; "" when unknown).
  const std::string& sequenceFolder() const { return sequence_folder_; }

  /// Maps to the end at up to `fps` frames per second (0: as fast as possible).
  void play();
  void pause();
  void setFps(float fps);
  /// Maps one more frame than asked for so far (two quick steps map two frames).
  void step();
  /// Maps until a frame starts a new keyframe (or the end).
  void stepToKeyframe();
  /// Moves to frame `frame` (0-based): forward maps up to it; backward re-maps from the start.
  void seek(int frame);
  /// Rebuilds the global map with new live thresholds (validated here, throws
  /// std::invalid_argument). The old map stays visible until the new one is swapped in.
  void setThresholds(const GlobalMapParams& thresholds);
  /// Re-maps the sequence from the start up to the current frame with new parameters.
  void rerun(const MapperParams& mapper);
  /// Moves a keyframe (pose correction) and rebuilds the global map. Errors go to status().
  void setKeyframePose(int id, const Transform& T_W_K);
  /// Replaces keyframe poses from a TUM trajectory file (KeyframeGraph::applyTrajectory).
  void loadTrajectory(const std::string& file);
  /// Runs `f` on the worker with the mapper and the current global map while nothing changes
  /// them (export, save); its exception text goes to status().error, its return to message.
  void withMapper(std::function<std::string(const Mapper&, const GlobalSnapshot&)> f);
  /// Shows the map as it was before the last pose-graph optimisation (true) or as it is: the
  /// global map and the selection are rebuilt from the unchanged local maps with the other
  /// keyframe poses. The Mapper's poses are never changed by it, so mapping goes on, exports and
  /// saves stay the optimised map. Without an optimisation it has no effect.
  void showBeforeOptimisation(bool before);
  /// The keyframe the inspector shows (-1: none; an id not mapped yet is kept and filled once it
  /// is). A change makes the worker publish a new selection().
  void selectKeyframe(int id);

  std::shared_ptr<const MappingSnapshot> mapping() const;
  /// Null until the first build.
  std::shared_ptr<const GlobalSnapshot> global() const;
  /// Whether the worker builds the point queries after every global map build (off by default:
  /// they cost memory and worker time only when the probe or the query slice is used). Turning
  /// them on builds them for the map shown (a rebuild of a session's global map).
  void wantQueries(bool on);
  /// Whether the worker builds the surface mesh with every global map, with `params` (off by
  /// default: the mesh layer costs worker time only while it is shown). Turning it on, or new
  /// params, rebuilds the map shown. A map file has no local maps: it never gets a mesh.
  void wantMesh(bool on, const MeshParams& params = {});
  /// The newest point queries; null until built (and while not wanted). Its generation may lag
  /// global()'s by one build while the queries are being built.
  std::shared_ptr<const QuerySnapshot> query() const;
  /// Null until the first build or selection.
  std::shared_ptr<const SelectionSnapshot> selection() const;
  PlayerStatus status() const;
  /// Blocks until the worker has nothing left to do (tests and the scripted path).
  void waitIdle();
  /// Called on the worker thread after each snapshot it publishes and when it falls idle
  /// (the window wakes its event loop with it). Set before the first command; must be cheap
  /// and thread-safe.
  void setOnChange(std::function<void()> on_change);

 private:
  void run();
  void mapOneFrame();
  void rebuildGlobal();
  // Builds the global map with the current keyframe poses, or those before the last
  // optimisation when asked and there was one (then the snapshot says so).
  // `with_graph`, if any, runs after the build with the graph at the poses it was built with.
  std::shared_ptr<GlobalSnapshot> buildGlobal(
      const GlobalMapParams& params, bool before_optimisation,
      const std::function<void(const KeyframeGraph&, const std::shared_ptr<GlobalSnapshot>&)>& with_graph = {});
  // Builds the surface mesh of `snap`'s map into it (worker thread; `graph` at its poses).
  void buildMesh(const KeyframeGraph& graph, const MeshParams& params, GlobalSnapshot& snap);
  // Builds and publishes the point queries of `snap` (worker thread; `graph` at its poses).
  void buildQueries(const KeyframeGraph& graph, const GlobalSnapshot& snap);
  // The poses MappingSnapshot::keyframes_before holds (worker thread).
  std::vector<Transform> posesBeforeOptimisation() const;
  // The scrubber position of a frame by its depth-list index.
  int positionOf(int frame_index) const;
  void restartMapper();
  // Fills trajectory_ from a saved session's mapper: every frame's pose when it stores them.
  void trajectoryOfSession();
  void publishMapping();
  void publishSelection();
  void notifyChange() const;  // calls on_change_ (mutex_ not held)
  void post(std::function<void()> command);
  void update(const std::function<void()>& change);  // under the lock, then wakes the worker
  // Under the lock: when `field` differs from `value`, sets it and `dirty`; then wakes the worker.
  template <class T>
  void setAndWake(T* field, T value, bool* dirty);
  bool workLeft() const;  // mutex_ held

  void start();
  int framesTotal() const { return sequence_ ? base_frames_ + static_cast<int>(sequence_->size()) : mapped_; }

  std::optional<Sequence> sequence_;
  std::shared_ptr<const Session> origin_;  // the saved session the mapper started from, if any
  std::vector<FrameEntry> session_truth_;  // its sequence's frames with ground truth, by time
  int base_frames_ = 0;                    // frames in the map before sequence_'s first entry
  int frames_with_groundtruth_ = 0;        // MappingSnapshot::frames_with_groundtruth
  std::string sequence_folder_;
  MapperParams mapper_params_;
  std::optional<MapRefinementParams> refine_;
  std::unique_ptr<Mapper> mapper_;  // worker thread only
  // Worker thread only: the global map's buffers and kept cells, reused by every rebuild (after
  // a loop closure it skips the filter and touches no new memory; costs the largest build's
  // buffers in resident memory, which grow with the map; docs/notes/performance.md has a figure).
  GlobalMapWorkspace global_workspace_;
  AppendLog<StageTimes> times_;                        // worker thread only (snapshots share it)
  AppendLog<TrajectoryPoint> trajectory_;              // worker thread only (snapshots share it)
  cv::Mat last_rgb_, last_depth_;                      // worker thread only
  int pose_edits_ = 0;                                 // worker thread only
  LastOptimisation refinement_;                        // worker thread only: the final refinement, once it moved poses
  int mapping_generation_ = 0, selection_serial_ = 0;  // worker thread only

  mutable std::mutex mutex_;
  std::condition_variable wake_, idle_;
  std::deque<std::function<void()>> commands_;
  GlobalMapParams thresholds_;
  int mapped_ = 0, target_ = 0;
  bool playing_ = false, stop_at_keyframe_ = false, global_dirty_ = false, working_ = false;
  bool stop_ = false;
  bool before_optimisation_ = false;
  int selected_keyframe_ = -1;
  bool selection_dirty_ = false;
  float fps_ = 0.f;
  std::chrono::steady_clock::time_point next_frame_time_{};
  std::chrono::steady_clock::time_point last_build_{};
  std::chrono::steady_clock::time_point last_edit_{};  // GlobalSnapshot::t_edit of the next build
  double last_build_s_ = 0;
  std::string error_, message_;
  std::shared_ptr<const MappingSnapshot> mapping_;
  std::shared_ptr<const GlobalSnapshot> global_;
  std::shared_ptr<const SelectionSnapshot> selection_;
  std::shared_ptr<const QuerySnapshot> query_;
  bool queries_wanted_ = false;
  bool mesh_wanted_ = false;
  MeshParams mesh_params_;
  int queries_tried_ = -1;         // static maps: the generation the queries were last built for (mutex_ held)
  bool staticQueriesDue() const {  // mutex_ held
    return static_map_ && queries_wanted_ && global_ && queries_tried_ != global_->generation;
  }
  std::function<void()> on_change_;
  int generation_ = 0;
  std::shared_ptr<const StaticMap> static_map_;  // static maps: what the worker shows
  void runStatic();                              // static maps: the worker's loop
  std::thread worker_;
};

}  // namespace vdmap::app::gui
