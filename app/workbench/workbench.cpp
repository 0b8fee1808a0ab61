#include "app/workbench/workbench.h"

#include <cmath>
#include <filesystem>

#include "app/cli/error_text.h"

namespace vdmap::app::gui {
namespace fs = std::filesystem;

const std::vector<std::pair<const char*, const char*>>& keyHelp() {
  static const std::vector<std::pair<const char*, const char*>> keys = {
      {"Space", "play / pause"},
      {"Right / Left", "one frame forward / back (taps add up, none is lost; back re-maps from the start)"},
      {"K", "map to the next keyframe"},
      {"F", "frame the map and the cameras (keeps the direction; the view follows the map again)"},
      {"R", "reset the view (default direction about the up axis)"},
      {"V", "view from the selected keyframe (its own intrinsics, letterboxed)"},
      {"C", "the selected keyframe's container view, large (zoom, cell grid, image bounds)"},
      {"B", "tracked poses: the map before / after the last pose-graph optimisation (loop closure)"},
      {"Ctrl+S",
       "save the view as a view file (View section) and print the `vdmap render` command that draws it (with Ctrl: "
       "a letter meant for a text field writes nothing)"},
      {"T", "frame the trajectories (tracked and ground truth) only"},
      {"PgUp / PgDn", "move the height slice up / down by its thickness (one floor)"},
      {"P, double-click", "turn about the point under the cursor (the eye stays)"},
      {"D", "show what the last threshold edit changed: kept grey, new green, removed or merged red"},
      {"Q", "probe under the cursor: free / occupied / unknown, distance (Alt+wheel: offset)"},
      {"Ctrl+1..9 / 1..9", "keep the view in quick view 1..9 / show it again (kept across runs)"},
      {"Ctrl+click", "measure: point A, then B (the distance shows in the view and the Measure section)"},
      {"H, F1", "show or hide these keys"},
      {"Esc", "close the help and the container view, leave \"view from keyframe\""},
      {"Ctrl+Z", "undo the last pose edit"},
      {"left drag", "orbit about the up axis (trackball: turn about the screen's axes)"},
      {"right / middle drag, Shift + left drag", "pan"},
      {"wheel", "zoom toward the point under the cursor"},
      {"click", "pick an ellipsoid (marked magenta; its keyframe is selected)"},
      {"container view: wheel, drag", "zoom, pan"},
  };
  return keys;
}

Workbench::Workbench(Settings settings, std::string warning) {
  UiState& ui = state_.ui;
  ui.settings = std::move(settings);
  ui.sequence_text = ui.settings.last_sequence;
  if (!warning.empty()) report(StatusLine::Kind::kWarning, std::move(warning));
}

std::shared_ptr<const MappingSnapshot> Workbench::mapping() const {
  return isOpen() ? state_.worker->mapping() : nullptr;
}

std::shared_ptr<const GlobalSnapshot> Workbench::global() const { return isOpen() ? state_.worker->global() : nullptr; }

std::shared_ptr<const SelectionSnapshot> Workbench::selection() const {
  return isOpen() ? state_.worker->selection() : nullptr;
}

void Workbench::setOnChange(std::function<void()> on_change) {
  state_.on_change = std::move(on_change);
  if (isOpen()) state_.worker->setOnChange(state_.on_change);
}

void Workbench::sync() {
  if (!isOpen()) return;
  queries_.sync();  // wanted by the probe or the slice; the slice's computation
  state_.worker->wantMesh(state_.ui.settings.show_mesh,
                          state_.ui.settings.mesh);  // the mesh layer: built with every map while shown
  poses_.sync();
  player_.sync();
  state_.edit_diff.sync(state_.worker->global());
  view_.sync();
}

void Workbench::noteAction() {
  StatusLine& status = state_.ui.status;
  if (!status.text.empty()) status = {StatusLine::Kind::kInfo, "", status.serial + 1};
}

void Workbench::key(KeyAction action) {
  UiState& ui = state_.ui;
  noteAction();
  switch (action) {
    case KeyAction::kPlayPause: player_.playPause(); break;
    case KeyAction::kStepForward: player_.step(); break;
    case KeyAction::kStepBack: player_.stepBack(); break;
    case KeyAction::kNextKeyframe: player_.stepToKeyframe(); break;
    case KeyAction::kFrameMap: view_.frameMap(); break;
    case KeyAction::kResetView: view_.resetView(); break;
    case KeyAction::kViewFromKeyframe:
      if (ui.selected_keyframe >= 0) ui.view_from_keyframe = ui.view_from_keyframe >= 0 ? -1 : ui.selected_keyframe;
      break;
    case KeyAction::kContainer:  // a map file has no containers (opening files)
      if (!staticMap()) ui.show_container = !ui.show_container;
      break;
    case KeyAction::kHelp: ui.show_help = !ui.show_help; break;
    case KeyAction::kEscape:
      ui.show_help = ui.show_container = false;
      ui.view_from_keyframe = -1;
      break;
    case KeyAction::kUndo: poses_.undoEdit(); break;
    case KeyAction::kBeforeOptimisation: poses_.showBeforeOptimisation(!ui.show_before_optimisation); break;
    case KeyAction::kSaveView: view_files_.saveSafely(ui.view_file_text); break;
    case KeyAction::kFrameTrajectories: view_.frameTrajectories(); break;
    case KeyAction::kPivotHere: ui.pivot_requested = true; break;  // the window probes the point under the cursor
    case KeyAction::kSliceUp: view_.moveSlice(1); break;
    case KeyAction::kSliceDown: view_.moveSlice(-1); break;
    case KeyAction::kProbe: ui.settings.probe = !ui.settings.probe; break;
    case KeyAction::kEditDiff: ui.show_edit_diff = !ui.show_edit_diff; break;
  }
}

void Workbench::enableSettingsAutosave(std::string file, Settings at_start) {
  view_files_.keepQuickViewsIn(fs::path(file).parent_path());
  autosave_file_ = std::move(file);
  autosave_.emplace(std::move(at_start));
}

double Workbench::autosaveSettings(SettingsAutosave::Clock::time_point now) {
  if (!autosave_ || autosave_file_.empty()) return INFINITY;
  autosave_->note(now, files_.savedSettings());
  if (autosave_->due(now)) {
    try {
      saveSettings();
    } catch (const std::exception& e) {
      state_.report(StatusLine::Kind::kWarning, std::string("settings not saved: ") + errorMessage(e));
      autosave_->saved();  // a failure is not retried every frame: the next change tries again
    }
  }
  const auto left = autosave_->dueIn(now);
  return left ? std::chrono::duration<double>(*left).count() : INFINITY;
}

void Workbench::saveSettings() {
  if (!autosave_ || autosave_file_.empty()) return;
  autosave_->note(SettingsAutosave::Clock::now(), files_.savedSettings());
  // Against what this run wrote last, so that a value put back (by hand or by Reset to
  // defaults) to what it was at the start replaces what was written meanwhile.
  saveChangedSettings(autosave_file_, autosave_->written(), autosave_->noted());
  autosave_->saved();
}

}  // namespace vdmap::app::gui
