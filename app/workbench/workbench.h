#pragma once
// The workbench's UI state and the actions it triggers, without a window: the ImGui code
// (workbench_window.cpp and the panels it draws) only edits UiState, calls these actions and reads
// the model through them, never the MappingWorker itself, so tests drive the same paths.
#include <array>
#include <ctime>
#include <filesystem>
#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/cli/sequence_args.h"
#include "app/workbench/mapping_worker.h"
#include "app/view/settings.h"
#include "app/workbench/settings_autosave.h"
#include "app/cli/parameter_table.h"
#include "mapping/files/map_file.h"
#include "render/map_mirror.h"
#include "render/query_slice.h"
#include "render/view_camera.h"
#include "render/view_framing.h"  // DrawnBounds (picture stream)
#include "render/view_spec.h"

namespace vdmap::app::gui {

/// The one status area: the last outcome of anything the user did (errors and successes).
struct StatusLine {
  enum class Kind { kInfo, kSuccess, kWarning, kError };
  Kind kind = Kind::kInfo;
  std::string text;  ///< empty: nothing to say
  int serial = 0;    ///< increases with every report (the window notices news by it)
};

/// What the probe found at one point (docs/workbench.md "Queries").
struct ProbeResult {
  glm::vec3 point{0.f};   ///< world, metres
  bool on_slice = false;  ///< on the query slice's plane (else in front of the surface under the cursor)
  Classification state;
  DistanceResult distance;
  int generation = 0;     ///< the global map whose queries answered (0: none built yet)
  std::string note;       ///< what is missing ("" when nothing): queries being built, no keyframes
  double query_us = 0;    ///< classify + distance of the point
  /// "free p=0.001 · 0.212 m to surface (kf 17) · x y z" (and the note).
  std::string text() const;
};

/// What only the UI edits (besides the persisted settings).
struct UiState {
  /// The user's settings: view options, and the parameters a newly opened sequence starts with.
  /// Parameters applied while a sequence is open go into them too, a saved session's never.
  Settings settings;
  /// The mapping parameters the sliders show: the open session's, as edited. A live one is sent
  /// at once (editParameter); a re-run one waits for rerun().
  ParameterValues params;
  render::OrbitCamera camera;
  /// The view frames the map whenever it grows, until the user orbits, pans or zooms;
  /// F (frame) and R (reset) turn it back on.
  bool follow_map = true;
  int view_from_keyframe = -1;    ///< >= 0: the 3-D view looks through this keyframe
  int selected_keyframe = -1;
  std::optional<Ellipsoid> picked;
  int picked_generation = 0;      ///< the global map it was picked in (a new map clears it)
  glm::vec3 pose_translation_m{0.f};  ///< the selected keyframe's pose as edited
  glm::vec3 pose_rotation_deg{0.f};   ///< roll (x), pitch (y, within +-90), yaw (z): R = Rz Ry Rx
  std::string sequence_text;      ///< the "open sequence" field
  std::string trajectory_text;    ///< the "load corrected trajectory" field
  std::string export_text = "vdmap_export";   ///< export folder
  std::string session_text = "map.vdmap";     ///< "save session" file
  std::string view_file_text = "vdmap_view.json";  ///< "save view" file (S)
  StatusLine status;
  /// Which settings this run started with (the note cmd_gui prints) and the file they are saved
  /// to on exit ("": not saved, a scripted run or --settings).
  std::string settings_source = "defaults", settings_file;
  bool show_help = false;         ///< the key and mouse overlay (H, F1)
  bool show_container = false;    ///< the large container view window (C)
  /// The map, keyframes and trajectory as they were before the last pose-graph optimisation
  /// (Workbench::showBeforeOptimisation); off again when there is none (after seeking back).
  bool show_before_optimisation = false;
  bool reset_layout = false;      ///< panels go back to their default widths next frame
  // The view tools: pick marker, keyframe list, measuring, quick views.
  /// The keyframe list scrolls to the selected keyframe once (set by a pick or a loop marker;
  /// Workbench::takeScrollToSelected clears it).
  bool scroll_to_selected = false;
  /// Measuring (Ctrl+click): point A, then B (world, metres); a third click starts again at A.
  std::optional<glm::vec3> measure_a, measure_b;
  bool measure_snap = false;      ///< measured points snap to the nearest ellipsoid centre
  bool pivot_requested = false;   ///< P: the window turns the view about the point under the cursor
  /// A file Save view was asked to write that exists: the window asks "Replace?" ("": none).
  std::string confirm_view_replace;
  bool load_view_thresholds = false;  ///< Load view: also its thresholds (as --settings does)
  int view_width = 1280, view_height = 720;  ///< the 3-D viewport in framebuffer pixels (the window sets it)
  // --- point queries (docs/workbench.md "Queries") ---
  bool probe = false;                ///< Q: what the map says under the cursor
  float probe_offset_m = 0.05f;      ///< the probe stands this far in front of the surface under the cursor
  std::optional<ProbeResult> probe_result;  ///< the last probe (cleared when the probe is turned off)
  bool query_slice = false;          ///< the query slice is drawn
  render::QuerySliceSpec query_slice_spec;
  // --- end point queries ---
};

/// The sigma the container window draws its ellipsoids at (scene_view.cpp's ContainerStyle), so
/// a container view file says it.
inline constexpr float kContainerSigma = 2.f;

/// Keyboard actions (the window maps keys to them; the help overlay lists them).
enum class KeyAction {
  kPlayPause, kStepForward, kStepBack, kNextKeyframe, kFrameMap, kResetView, kViewFromKeyframe, kContainer, kHelp,
  kEscape, kUndo, kBeforeOptimisation, kSaveView, kFrameTrajectories, kPivotHere,
  kSliceUp, kSliceDown,  // height slice: PgUp / PgDn
  kProbe                 // point queries: Q
};

/// The keys and mouse actions, for the help overlay and docs/workbench.md: {keys, what they do}.
const std::vector<std::pair<const char*, const char*>>& keyHelp();

/// Picks the ellipsoid whose mean projects nearest to pixel (x, y) of `view` within
/// `radius_px`, preferring the nearer one among those within a pixel of the best; -1 if none.
int pickEllipsoid(const std::vector<Ellipsoid>& ellipsoids, const render::ViewCamera& view, float x_px,
                  float y_px, float radius_px = 8.f);

/// The loop strip's markers (view pixels along the strip, in time order) merged where they lie
/// closer than `min_px`: each cluster's centre and the indices of its markers.
struct MarkerCluster {
  float x = 0;
  std::vector<int> members;
};
std::vector<MarkerCluster> clusterMarkers(const std::vector<float>& positions_px, float min_px);

/// Where a screenshot goes by default: $XDG_PICTURES_DIR/vdmap, else ~/Pictures/vdmap, else the
/// working folder ("" for none of the first two).
std::filesystem::path screenshotFolder();
/// A name in `folder` that does not exist yet: STEM-YYYYMMDD-HHMMSS.png for local time `when`, with
/// -2, -3 ... appended while one exists.
std::filesystem::path freeTimestampedName(const std::filesystem::path& folder, std::time_t when,
                                          const std::string& stem = "vdmap");
/// The file a screenshot with no name typed goes to: a free timestamped name in
/// screenshotFolder() (created), else in the working folder when that cannot be made.
std::filesystem::path defaultScreenshotFile(std::time_t when);
/// `file` itself when it does not exist, else FILE-2.EXT, FILE-3.EXT ... (the first free one).
std::filesystem::path freeNumberedName(const std::filesystem::path& file);

/// Euler angles (deg, R = Rz Ry Rx) <-> rotation. rotationToEulerDeg gives pitch (y) within
/// [-90, 90] and roll, yaw within (-180, 180]; at +-90 pitch (gimbal lock) roll is 0.
glm::vec3 rotationToEulerDeg(const Eigen::Matrix3d& R);
Eigen::Matrix3d eulerDegToRotation(const glm::vec3& deg);

/// The 3-D view's camera in a viewport, and where its image lies in the viewport (all of it,
/// or the letterbox of "view from keyframe").
struct ViewportView {
  render::ViewCamera camera;
  render::PixelRect image;  ///< top-left origin, viewport pixels
};

class Workbench {
 public:
  /// `settings`: what the window starts with (the saved settings with any --set applied).
  explicit Workbench(Settings settings, std::string warning = {});

  UiState& ui() { return ui_; }
  const UiState& ui() const { return ui_; }
  /// Null while no sequence is open. The window does not use it (it goes through the methods
  /// below); tests reach the model with it.
  MappingWorker* worker() { return worker_.get(); }

  /// Whether a sequence or saved session is open.
  bool isOpen() const { return worker_ != nullptr; }
  /// 1, 2, ... per sequence or session opened (0 while none): snapshots' generations restart with
  /// each, so what mirrors them keys on this too.
  int sessionSerial() const { return session_serial_; }
  /// The open sequence (null while none is open, and for a saved session without its frames).
  const TumSequence* sequence() const { return worker_ ? worker_->sequence() : nullptr; }
  /// The newest snapshots of the open session (null while none is open; global() and selection()
  /// also until the first build). Thread-safe; each holds its snapshot while it is used.
  std::shared_ptr<const MappingSnapshot> mapping() const;
  std::shared_ptr<const GlobalSnapshot> global() const;
  std::shared_ptr<const SelectionSnapshot> selection() const;
  /// The player's state (all default while nothing is open).
  PlayerStatus player() const;
  /// Plays to the end at the fps limit / pauses (nothing while nothing is open).
  void play();
  void pause();
  /// Moves the player to frame `frame` (0-based): forward maps up to it, backward re-maps from
  /// the first frame (MappingWorker::seek).
  void seek(int frame);
  /// Sets the playback limit in frames per second (0: as fast as mapping goes) for the open
  /// sequence and the ones opened later (it is a setting).
  void setFps(float fps);
  /// Selects keyframe `id` even when it is not mapped yet (the scripted run's --keyframe): the
  /// inspector shows it once it is. Unlike selectKeyframe, the pose fields are not filled here.
  void preselectKeyframe(int id);
  /// Called on the worker's thread whenever the open session (and any opened later) publishes
  /// news or falls idle; the window wakes its event loop with it. Must be cheap and thread-safe;
  /// nullptr removes it.
  void setOnChange(std::function<void()> on_change);

  /// Shows `text` in the status area (errors stay until the next report).
  void report(StatusLine::Kind kind, std::string text);
  /// The first error reported since construction ("" if none): a scripted run fails on it.
  const std::string& firstError() const { return first_error_; }

  /// Opens a sequence (replacing the current one). On failure the current one stays, the
  /// message goes to the status line and false is returned: a bad folder never ends the app.
  /// With tracked poses, its keyframe poses are refined after the last frame as setRefinement says
  /// (args.refine is not looked at: the command line's holds for every sequence of the run).
  bool open(const SequenceArgs& args);
  /// The refinement of tracked keyframe poses after the last frame (nullopt: none) for the
  /// sequences and sessions opened from now on (default: joint, as `vdmap map`).
  void setRefinement(std::optional<MapRefinementParams> refine) { refine_ = std::move(refine); }
  /// Opens a saved session (.vdmap) the same way: its keyframes and saved thresholds, no player.
  bool openSession(const std::string& file);
  /// The thresholds `file` sets (--settings FILE: a settings.json or a view file, readSettingsArg)
  /// go over the saved thresholds of every session opened from now on; "": none.
  void setSessionSettings(std::string file) { session_settings_ = std::move(file); }
  // --- Opening files: map files, drop, recent (workbench_files.cpp) ---
  /// Opens whatever `path` holds (detectMapFile): a sequence folder (open), a session
  /// (openSession), a map folder, ellipsoid or point PLY or OctoMap (openMapFile), or a view file
  /// (applied as Load view does: the camera and view options, not its thresholds). On success
  /// the path goes to the front of settings().recent. Failures go to the status line (false).
  bool openPath(const std::string& path);
  /// Opens a map file as a static map: one mapping snapshot (keyframe poses, edges and
  /// trajectory when the file has them) and one global map, nothing to play, rebuild or edit.
  bool openMapFile(const std::string& path);
  /// The same for a map read already (vdmap gui PATH reads it before the window opens).
  bool openMapFile(std::shared_ptr<const StaticMap> map);
  /// The open static map (null while nothing, a sequence or a session is open).
  const StaticMap* staticMap() const { return worker_ ? worker_->staticMap() : nullptr; }
  /// The tooltip of what a static map disables (thresholds, re-map, inspector, container, poses).
  static constexpr const char* kStaticMapWhy = "a map file has no local maps to rebuild from";
  /// Queues a path dropped on the window (or given by --drop); the next frame opens the queue in
  /// order (openDropped), so a drop never opens in the middle of drawing one.
  void drop(std::string path) { dropped_.push_back(std::move(path)); }
  /// Opens the queued drops (openPath each); returns how many were taken. Once per UI frame.
  int openDropped();
  // --- end opening files ---
  /// Writes what `vdmap map` writes into ui().export_text (on the worker; the outcome shows in
  /// the status line with the absolute path).
  void exportMap();
  /// Saves the session (.vdmap) into ui().session_text (on the worker, like exportMap).
  void saveSession();
  /// Sends the edited thresholds (ui().params.global) to the session (a bad value goes to the
  /// status line); while a sequence is open they become the user's settings too.
  void applyThresholds();
  /// Re-maps the sequence with the edited re-run parameters (ui().params.mapper); while a
  /// sequence is open they become the user's settings too.
  void rerun();
  /// Sets parameter `p` as edited on a slider, checked as everywhere else (a refused value goes
  /// to the status line and false is returned, the edit is dropped). Live ones are applied at
  /// once; re-run ones stay pending until rerun().
  bool editParameter(const Parameter& p, double value);
  /// Whether `p` as edited is not (yet) what the shown map was made with: a re-run parameter not
  /// re-run, or a threshold whose rebuild has not arrived.
  bool pending(const Parameter& p) const;
  /// The value of `p` the shown map was made with (the slider's value when nothing is pending).
  double inUse(const Parameter& p) const;
  /// True while a saved session (no sequence) is open: nothing to play or re-run.
  bool savedSession() const { return worker_ && !worker_->sequence(); }
  /// Why the open saved session cannot continue mapping (its player is off), e.g. "mapped to the
  /// end of SEQ (503 of 503 frames): nothing to continue"; "" when it continues or no session is open.
  const std::string& whyPlayerOff() const { return why_player_off_; }
  /// Thresholds, re-run parameters and view options back to their defaults (window size, last
  /// sequence and recent files kept); the thresholds are applied and the layout reset.
  void resetToDefaults();
  /// Selects keyframe `id` for the inspector and tells the session (an id not mapped: none).
  /// `scroll`: the keyframe list scrolls to it once (a pick in the view, a loop marker).
  void selectKeyframe(int id, bool scroll = false);
  /// Sends ui().pose_* as the selected keyframe's new pose.
  void applyPoseEdit();
  /// Remembers the selected keyframe's pose before an edit starts (a drag's first frame), so
  /// undoPoseEdit can put it back.
  void beginPoseEdit();
  /// Puts back the pose from before the last edit (returns false when there is none).
  bool undoPoseEdit();
  bool canUndoPoseEdit() const { return !pose_undo_.empty(); }
  /// Refills ui().pose_* when the selected keyframe's pose changed under them (a re-run, a
  /// trajectory file, seeking back, or a keyframe selected before it was mapped), so an edit
  /// starts from the pose shown.
  void syncPoseFields();
  void loadTrajectory();
  /// Shows the map before the last pose-graph optimisation (true) or after; refused (false
  /// returned, status line says why) when there was no optimisation.
  bool showBeforeOptimisation(bool before);
  /// Whether the open session has had a pose-graph optimisation (the toggle above can act).
  bool canShowBeforeOptimisation() const;
  /// The keyframe graph of `mapping` as the 3-D view draws it now: keyframe poses, covisibility
  /// and loop edges, trajectory (before the last optimisation when ui().show_before_optimisation)
  /// and the ground truth (tracked poses, when the sequence has one and the setting shows it).
  render::GraphScene graphScene(const MappingSnapshot& mapping) const;

  /// Once per UI frame: pose fields, the session's news into the status line, the pick cleared
  /// when the map changed, and the view re-framed while it follows the map.
  void sync();
  /// Frames the map (and the trajectory) in the 3-D viewport keeping the viewing direction, and
  /// follows the map again (F).
  void frameMap();
  /// The default view of the whole map about the up axis, following the map again (R).
  void resetView();
  /// The user orbits, pans or zooms: the view stops following the map and leaves "view from
  /// keyframe".
  void orbit(float d_yaw, float d_pitch);
  void pan(float dx_px, float dy_px);
  void zoom(float wheel_steps);
  /// The world's up direction for the view: the setting, or estimated from the data.
  glm::vec3 upVector() const;
  /// One keyboard action.
  void key(KeyAction action);

  // The view tools (zoom at the cursor, pivot, drag speed, measuring, view files, quick views).
  /// Zooms by `wheel_steps` toward `p` (world): the point under the cursor stays under it.
  void zoomAt(float wheel_steps, const glm::vec3& p);
  /// The point of the target's plane (facing the view) under pixel (x, y) of a width x height
  /// viewport: where zoomAt and pivotAt go when there is no surface under the cursor.
  glm::vec3 targetPlanePoint(float x_px, float y_px, int width, int height) const;
  /// Turns about `p`: the target moves there, the eye stays (double-click, P).
  void pivotAt(const glm::vec3& p);
  /// Frames the trajectory and the ground truth only (T), keeping the direction.
  void frameTrajectories();
  /// Metres per pixel of a pose drag: the view's at the selected keyframe's depth, within
  /// 0.1 mm..5 cm.
  float poseDragSpeed() const;
  /// Whether the keyframe list should scroll to the selection now (once per pick or marker).
  bool takeScrollToSelected();
  /// Ctrl+click: the next measuring point (A, then B, then A again). With ui().measure_snap it
  /// snaps to the nearest ellipsoid centre of the global map.
  void addMeasurePoint(const glm::vec3& p);
  /// Reads `file` (a view file) and shows its view (applyViewSpec); with `thresholds` its
  /// thresholds are applied too. A view whose size is not the viewport's warns (the picture
  /// differs from `vdmap render --view-file`). False (the status line says why) on failure.
  bool loadView(const std::string& file, bool thresholds);
  /// Warns (true) when `asked`'s size is not the viewport's (loadView, --view-file).
  bool warnAboutTheViewsSize(const render::ViewSpec& asked);
  /// Ctrl+1..9 keep the view shown in memory; 1..9 show it again (false: none kept there).
  void storeQuickView(int slot);
  bool recallQuickView(int slot);
  /// The window saves the settings while it runs, 1 s after the last change (SettingsAutosave):
  /// into `file`, what changed since `at_start` (saveChangedSettings).
  void enableSettingsAutosave(std::string file, Settings at_start);
  /// Once per turn of the event loop: saves when due. Returns the seconds until the next save
  /// is due (the loop's longest wait; infinity: nothing to save).
  double autosaveSettings(SettingsAutosave::Clock::time_point now);
  /// The banner over the view while the map before the last optimisation shows ("" while not).
  std::string beforeOptimisationBanner(const MappingSnapshot& mapping) const;

  /// The view shown, as a view file holds it (docs/workbench.md "Save view"): container:K while
  /// the container window is open (2W x 2H), keyframe:K while viewing from a keyframe (the
  /// letterbox's size), else the global view with its camera (eye, target, up, field of view) at
  /// the viewport's size; the view options and the selected keyframe from the settings and UI.
  render::ViewSpec viewSpec() const;
  /// Shows `spec` (the inverse of viewSpec, but the size: the window's viewport stays as laid
  /// out): the view options go into the settings, the camera as given (else the default view,
  /// turned by spec.orbit), and the view stops following the map. Keyframe and container views
  /// select their keyframe (an id not mapped: the global view, and false is returned). The
  /// thresholds stay: a view file's apply only through --settings.
  bool applyViewSpec(const render::ViewSpec& spec);
  /// The file a render command names for the open session: the .vdmap or sequence folder.
  const std::string& viewSource() const { return ui_.settings.last_sequence; }
  /// Writes viewSpec() and the thresholds as a view file to `file`; the status line and stdout
  /// give its absolute path and the `vdmap render` command that draws it. False (the status line
  /// says why) when nothing is open or the file cannot be written.
  bool saveView(const std::string& file);
  /// As saveView, but never overwrites silently: the default name (vdmap_view.json) takes the
  /// first free number (vdmap_view-2.json ...); another name that exists is written only with
  /// `replace`, else ui().confirm_view_replace asks and false is returned.
  bool saveViewSafely(const std::string& file, bool replace = false);

  // --- picture stream (framing what is drawn, height slice) ---
  /// What the 3-D view draws of the global map, boxed (render::drawnBounds at the settings'
  /// sigma, draw mode and slice): what F frames and the layout self-check projects.
  render::DrawnBounds drawnMap() const;
  /// The strays the last F / R / follow left out of the frame (the hint line counts them).
  std::size_t framedStrays() const { return framed_strays_; }
  // --- end picture stream ---

  // --- height slice ---
  /// The global map's height frame about upVector(): heights above its floor colour the map
  /// (colour "height") and bound the slice. Computed once per map and up direction.
  render::HeightFrame heightFrame() const;
  /// What the 3-D view draws and picks of the global map: all of it, or with the settings' slice
  /// on the ellipsoids it keeps (render::slicedMap, as `vdmap render --slice`). `serial` is
  /// new whenever the selection is (a new map, up direction or slice). Null while none is open.
  struct ShownMap {
    std::shared_ptr<const std::vector<Ellipsoid>> ellipsoids;
    int serial = 0;
  };
  glm::vec3 framingUp() const;  // upVector(), from heightFrame's cache when it holds it
  ShownMap shownMap() const;
  /// PgUp / PgDn: the slice moves up (+1) or down (-1) by its thickness (one floor at a time).
  void moveSlice(int direction);
  // --- end height slice ---

  // --- point queries (workbench_queries.cpp; docs/workbench.md "Queries") ---
  /// The newest point queries of the open session (null while none are built: they are built
  /// while the probe or the query slice is on). sync() asks the worker for them.
  std::shared_ptr<const QuerySnapshot> query() const;
  /// The probe's point for pixel (x, y) of a width x height viewport: on the query slice's plane
  /// while it is shown, else `surface` (the drawn surface under the pixel) moved toward the eye
  /// by ui().probe_offset_m; nullopt when neither exists.
  std::optional<glm::vec3> probePoint(float x_px, float y_px, int width, int height,
                                      const std::optional<glm::vec3>& surface) const;
  /// Classifies `p` and its distance to the nearest surface with query() (a note says why when
  /// none is built).
  ProbeResult probe(const glm::vec3& p, bool on_slice = false) const;
  /// The probe under pixel (x, y) into ui().probe_result (reset when there is no point there);
  /// returns whether the text shown changed.
  bool probeAt(float x_px, float y_px, int width, int height, const std::optional<glm::vec3>& surface);
  /// The query slice drawn now (null: none yet, or off). sync() starts its computation off the UI
  /// thread when the map, the spec or the up axis changed; the window is woken when it is done.
  std::shared_ptr<const render::QuerySliceImage> querySlice() const { return ui_.query_slice ? slice_image_ : nullptr; }
  /// Blocks until the slice being computed (if any) is taken (tests and scripted runs).
  void waitQuerySlice();
  // --- end point queries ---

  /// The 3-D view in a viewport of width x height (framebuffer pixels).
  ViewportView view(int width, int height) const;
  /// Click in the 3-D view at (x, y) of a width x height viewport: sets ui().picked and selects
  /// the ellipsoid's keyframe; a click on nothing clears the pick.
  void pick(float x_px, float y_px, int width, int height);

 private:
  void opened(const std::string& path);
  void showPose(const Transform& T_W_K);
  void sendPose(int id, const Transform& T_W_K);
  // The box the view frames: drawnMap() (strays left out, so a few far ellipsoids do not shrink
  // the map to a dot), grown to hold every camera of the trajectory and every keyframe's frustum
  // as drawn. `strays` receives drawnMap's count.
  render::FrameBox frameBounds(std::size_t* strays = nullptr) const;

  UiState ui_;
  std::string first_error_;
  Transform pose_shown_ = Transform::Identity();  // what ui().pose_* were filled from or sent as
  int pose_edits_sent_ = 0;                        // to this session (MappingSnapshot::pose_edits)
  std::vector<std::pair<int, Transform>> pose_undo_;  // (keyframe, pose before the edit)
  std::string shown_error_, shown_message_;        // the session's, already reported
  int framed_generation_ = -1;                     // the global map the view was last framed on
  std::pair<int, int> framed_size_{0, 0};          // and the viewport it was framed in
  std::size_t framed_strays_ = 0;                  // picture stream: left out of that frame
  // Height slice: heightFrame's and shownMap's cache, keyed by the global snapshot and the up.
  struct SliceCache {
    std::shared_ptr<const GlobalSnapshot> global;
    std::shared_ptr<const MappingSnapshot> mapping;  // its cameras give the data up axis
    UpAxis axis = UpAxis::kData;
    int serial = 0;
    render::HeightFrame frame;
    render::HeightSlice slice;
    ShownMap shown;
  };
  mutable SliceCache slice_cache_;
  std::optional<MapRefinementParams> refine_ = MapRefinementParams{};  // setRefinement's
  std::function<void()> on_change_;                // setOnChange's, given to every new worker
  std::string session_settings_;                   // setSessionSettings'
  std::string why_player_off_;                     // whyPlayerOff()
  std::array<std::optional<render::ViewSpec>, 9> quick_views_;  // storeQuickView's
  std::optional<SettingsAutosave> autosave_;       // enableSettingsAutosave's
  std::string autosave_file_;
  Settings autosave_start_;

  // Point queries: the slice shown, the one being computed and what it is computed for.
  struct SliceKey {
    std::shared_ptr<const QueryMap> map;  // held: a new map at the same address is not the same map
    render::QuerySliceSpec spec;
    render::HeightFrame height;
    bool operator==(const SliceKey&) const = default;
  };
  void syncQueries();
  std::shared_ptr<const render::QuerySliceImage> slice_image_;
  std::future<std::shared_ptr<const render::QuerySliceImage>> slice_job_;
  SliceKey slice_key_, slice_job_key_;

  int session_serial_ = 0;
  std::unique_ptr<MappingWorker> worker_;
  std::vector<std::string> dropped_;  // drop()'s, not opened yet (workbench_files.cpp)
};

}  // namespace vdmap::app::gui
