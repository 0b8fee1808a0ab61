#pragma once
// The workbench's model without a window: the UI state and the controllers whose actions it
// triggers. The ImGui code (workbench_window.cpp and the panels it draws) only edits UiState, calls
// these actions and reads the model through them, never the MappingWorker itself, so tests drive
// the same paths.
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "app/view/settings.h"
#include "app/workbench/file_actions.h"
#include "app/workbench/parameter_editor.h"
#include "app/workbench/player.h"
#include "app/workbench/pose_editor.h"
#include "app/workbench/query_controller.h"
#include "app/workbench/settings_autosave.h"
#include "app/workbench/view_controller.h"
#include "app/workbench/view_files.h"
#include "app/workbench/workbench_state.h"

namespace vdmap::app::gui {

/// Keyboard actions (the window maps keys to them; the help overlay lists them).
enum class KeyAction {
  kPlayPause,
  kStepForward,
  kStepBack,
  kNextKeyframe,
  kFrameMap,
  kResetView,
  kViewFromKeyframe,
  kContainer,
  kHelp,
  kEscape,
  kUndo,
  kBeforeOptimisation,
  kSaveView,
  kFrameTrajectories,
  kPivotHere,
  kSliceUp,
  kSliceDown,  // height slice: PgUp / PgDn
  kProbe,      // point queries: Q
  kEditDiff    // what the last threshold edit changed: D
};

/// The keys and mouse actions, for the help overlay and docs/workbench.md: {keys, what they do}.
const std::vector<std::pair<const char*, const char*>>& keyHelp();

/// Owns the shared state (WorkbenchState) and the controllers that act on it: player(),
/// files(), parameters(), poses(), view(), viewFiles(), queries(). UI thread only.
class Workbench {
 public:
  /// `settings`: what the window starts with (the saved settings with any --set applied).
  explicit Workbench(Settings settings, std::string warning = {});
  Workbench(const Workbench&) = delete;  // the controllers hold references into it
  Workbench& operator=(const Workbench&) = delete;

  UiState& ui() { return state_.ui; }
  const UiState& ui() const { return state_.ui; }
  /// Null while no sequence is open. The window does not use it (it goes through the
  /// controllers); tests reach the model with it.
  MappingWorker* worker() { return state_.worker.get(); }

  /// Whether a sequence, saved session or map file is open.
  bool isOpen() const { return state_.worker != nullptr; }
  /// 1, 2, ... per sequence or session opened (0 while none): snapshots' generations restart with
  /// each, so what mirrors them keys on this too.
  int sessionSerial() const { return state_.session_serial; }
  /// The open sequence (null while none is open, and for a saved session without its frames).
  const Sequence* sequence() const { return isOpen() ? state_.worker->sequence() : nullptr; }
  /// The open static map (null while nothing, a sequence or a session is open).
  const StaticMap* staticMap() const { return state_.staticMap(); }
  /// True while a saved session (no sequence) is open: nothing to play or re-run.
  bool savedSession() const { return state_.savedSession(); }
  /// The newest snapshots of the open session (null while none is open; global() and selection()
  /// also until the first build). Thread-safe; each holds its snapshot while it is used.
  std::shared_ptr<const MappingSnapshot> mapping() const;
  std::shared_ptr<const GlobalSnapshot> global() const;
  std::shared_ptr<const SelectionSnapshot> selection() const;
  /// Called on the worker's thread whenever the open session (and any opened later) publishes
  /// news or falls idle; the window wakes its event loop with it. Must be cheap and thread-safe;
  /// nullptr removes it.
  void setOnChange(std::function<void()> on_change);

  /// Shows `text` in the status area (it stays until the next report or action).
  void report(StatusLine::Kind kind, std::string text) { state_.report(kind, std::move(text)); }
  /// The first error reported since construction ("" if none): a scripted run fails on it.
  const std::string& firstError() const { return state_.first_error; }

  /// Once per UI frame: the point queries, the pose fields, the session's news into the status
  /// line, the pick cleared when the map changed, and the view re-framed while it follows the map.
  void sync();
  /// One keyboard action (a new action: noteAction first).
  void key(KeyAction action);
  /// The user starts a new action (a key, a click): the status line's message,
  /// the outcome of an earlier one, goes; what this action reports shows until the next one.
  void noteAction();

  /// The window saves the settings while it runs, 1 s after the last change (SettingsAutosave):
  /// into `file`, what differs from what the file got from this run, at first `at_start`
  /// (saveChangedSettings). Quick views are kept beside it (ViewFiles::keepQuickViewsIn).
  void enableSettingsAutosave(std::string file, Settings at_start);
  /// Once per turn of the event loop: saves when due. Returns the seconds until the next save
  /// is due (the loop's longest wait; infinity: nothing to save).
  double autosaveSettings(SettingsAutosave::Clock::time_point now);
  /// Saves what changed now, due or not (on exit). Throws std::runtime_error naming the file.
  void saveSettings();

  Player& player() { return player_; }
  const Player& player() const { return player_; }
  FileActions& files() { return files_; }
  ParameterEditor& parameters() { return parameters_; }
  PoseEditor& poses() { return poses_; }
  ViewController& view() { return view_; }
  const ViewController& view() const { return view_; }
  ViewFiles& viewFiles() { return view_files_; }
  QueryController& queries() { return queries_; }

 private:
  WorkbenchState state_;
  Player player_{state_};
  ParameterEditor parameters_{state_, player_};
  PoseEditor poses_{state_};
  ViewController view_{state_, poses_};
  ViewFiles view_files_{state_, view_, parameters_};
  QueryController queries_{state_, view_};
  FileActions files_{state_, view_, [this] {
                       player_.newSession();
                       poses_.newSession();
                       view_.newSession();
                     }};
  std::optional<SettingsAutosave> autosave_;  // enableSettingsAutosave's
  std::string autosave_file_;
};

}  // namespace vdmap::app::gui
