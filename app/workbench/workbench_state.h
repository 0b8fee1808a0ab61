#pragma once
// What the Workbench's controllers share, without a window: the UI state only the ImGui code
// edits, the open session's worker and the status line.
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "app/cli/parameter_table.h"
#include "app/cli/sequence_args.h"
#include "app/view/settings.h"
#include "app/workbench/edit_diff.h"
#include "app/workbench/mapping_worker.h"
#include "render/query_slice.h"
#include "render/view_camera.h"

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
  int generation = 0;   ///< the global map whose queries answered (0: none built yet)
  std::string note;     ///< what is missing ("" when nothing): queries being built, no keyframes
  double query_us = 0;  ///< classify + distance of the point
  /// "free p=0.001 · 0.212 m to surface (kf 17) · x y z" (and the note).
  std::string text() const;
};

/// What only the UI edits (besides the persisted settings).
struct UiState {
  /// The user's settings: view options, and the parameters a newly opened sequence starts with.
  /// Parameters applied while a sequence is open go into them too, a saved session's never.
  Settings settings;
  /// The mapping parameters the sliders show: the open session's, as edited. A live one is sent
  /// at once (ParameterEditor::edit); a re-run one waits for ParameterEditor::rerun.
  ParameterValues params;
  render::OrbitCamera camera;
  /// The view frames the map whenever it grows, until the user orbits, pans or zooms;
  /// F (frame) and R (reset) turn it back on.
  bool follow_map = true;
  int view_from_keyframe = -1;  ///< >= 0: the 3-D view looks through this keyframe
  int selected_keyframe = -1;
  std::optional<Ellipsoid> picked;
  int picked_generation = 0;                       ///< the global map it was picked in (a new map clears it)
  glm::vec3 pose_translation_m{0.f};               ///< the selected keyframe's pose as edited
  glm::vec3 pose_rotation_deg{0.f};                ///< roll (x), pitch (y, within +-90), yaw (z): R = Rz Ry Rx
  std::string sequence_text;                       ///< the "open sequence" field
  std::string trajectory_text;                     ///< the "load corrected trajectory" field
  std::string export_text = "vdmap_export";        ///< export folder
  std::string session_text = "map.vdmap";          ///< "save session" file
  std::string view_file_text = "vdmap_view.json";  ///< "save view" file (Ctrl+S)
  StatusLine status;
  /// Which settings this run started with (the note cmd_gui prints) and the file they are saved
  /// to on exit ("": not saved, a scripted run or --settings).
  std::string settings_source = "defaults", settings_file;
  bool show_help = false;       ///< the key and mouse overlay (H, F1)
  bool show_container = false;  ///< the large container view window (C)
  /// The map, keyframes and trajectory as they were before the last pose-graph optimisation
  /// (PoseEditor::showBeforeOptimisation); off again when there is none (after seeking back).
  bool show_before_optimisation = false;
  /// The 3-D view shows what the last threshold edit changed (D; EditDiffTracker).
  bool show_edit_diff = false;
  bool reset_layout = false;  ///< panels go back to their default widths next frame
  // The view tools: pick marker, keyframe list, measuring, quick views.
  /// The keyframe list scrolls to the selected keyframe once (set by a pick or a loop marker;
  /// PoseEditor::takeScrollToSelected clears it).
  bool scroll_to_selected = false;
  /// Measuring (Ctrl+click): point A, then B (world, metres); a third click starts again at A.
  std::optional<glm::vec3> measure_a, measure_b;
  bool measure_snap = false;     ///< measured points snap to the nearest ellipsoid centre
  bool pivot_requested = false;  ///< P: the window turns the view about the point under the cursor
  /// A file Save view was asked to write that exists: the window asks "Replace?" ("": none).
  std::string confirm_view_replace;
  bool load_view_thresholds = false;         ///< Load view: also its thresholds (as --settings does)
  int view_width = 1280, view_height = 720;  ///< the 3-D viewport in framebuffer pixels (the window sets it)
  // Point queries (docs/workbench.md "Queries"): the probe and the query slice are settings.
  std::optional<ProbeResult> probe_result;  ///< the last probe (cleared when the probe is turned off)
};

/// The sigma the container window draws its ellipsoids at (scene_view.cpp's ContainerStyle), so
/// a container view file says it.
inline constexpr float kContainerSigma = 2.f;

/// The tooltip of what a static map disables (thresholds, re-map, inspector, container, poses).
inline constexpr const char* kStaticMapWhy = "a map file has no local maps to rebuild from";

/// `path` absolute and normal, as the status line names files ("" stays "").
std::string absolutePath(const std::string& path);

/// Tells a double click by the presses' own times (GLFW's callbacks) rather than by the frames
/// that see them: a frame slower than the clicks sees the button held once (Dear ImGui 1.86 only
/// looks at which buttons are down when a frame starts) and a double click was lost.
class DoubleClick {
 public:
  /// A press of the left button at `t_s` seconds at (x, y) pixels: true when it is the second of
  /// a double click (within 0.4 s and 6 pixels of the first); a third starts again.
  bool press(double t_s, double x, double y);

 private:
  double last_t_ = -1e9, last_x_ = 0, last_y_ = 0;
};

/// `text` broken into lines (joined by '\n') no wider than `width` as `measure` gives a piece's
/// width: after a space or a '/' (so a path breaks between its folders, never inside a name),
/// inside a piece only when it alone is wider than a line.
std::string breakLines(const std::string& text, float width, const std::function<float(std::string_view)>& measure);

/// What the Workbench's controllers share (the Workbench owns it; the UI thread alone uses it).
struct WorkbenchState {
  UiState ui;
  /// The open sequence's, session's or map file's worker; null while none is open.
  std::unique_ptr<MappingWorker> worker;
  /// 1, 2, ... per sequence, session or map file opened (0 while none).
  int session_serial = 0;
  /// Called on the worker's thread on news (Workbench::setOnChange); every new worker gets it.
  std::function<void()> on_change;
  std::string first_error;  ///< the first error reported ("" if none)
  /// How the open sequence was opened (folder, --frames, --camera, ...), which a printed render
  /// command repeats; an empty folder for a session or a map file.
  SequenceArgs opened_args;
  /// The thresholds `vdmap render` starts from for what is open: the defaults for a sequence, the
  /// saved ones for a session; none for a map file (it has no thresholds).
  std::optional<GlobalMapParams> render_thresholds;
  /// What the last threshold edit changed (ParameterEditor sends edits, Workbench::sync follows).
  EditDiffTracker edit_diff;

  /// Shows `text` in the status line (it stays until the next report or action).
  void report(StatusLine::Kind kind, std::string text);
  /// The open static map (null while nothing, a sequence or a session is open).
  const StaticMap* staticMap() const { return worker ? worker->staticMap() : nullptr; }
  /// True while a saved session (no sequence) is open: nothing to play or re-run.
  bool savedSession() const { return worker && !worker->sequence(); }
};

}  // namespace vdmap::app::gui
