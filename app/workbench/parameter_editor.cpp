#include "app/workbench/parameter_editor.h"

#include "app/cli/error_text.h"

namespace vdmap::app::gui {

std::string parameterHelp(const Parameter& p) {
  return std::string(p.help) + "\n\nvalid: " + validityText(p) + "; default " + formatValue(p, defaultValue(p)) +
         " (def puts it back); `vdmap map " + std::string(p.flag) + "`, --set / settings.json " +
         (p.live ? "thresholds." : "rerun.") + std::string(p.key) + ".";
}

double defaultValue(const Parameter& p) { return p.get(ParameterValues{}); }

bool ParameterEditor::edit(const Parameter& p, double value) {
  UiState& ui = state_.ui;
  ParameterValues edited = ui.params;
  try {
    checkValue(p, value);
    p.set(edited, value);
    validate(edited);
  } catch (const std::exception& e) {
    state_.report(StatusLine::Kind::kError, errorMessage(e));
    return false;
  }
  ui.params = edited;
  if (!state_.worker) {  // nothing open: what the next sequence opened starts with
    ui.settings.thresholds = edited.global;
    ui.settings.mapper = edited.mapper;
  } else if (p.live) {
    applyThresholds();
  }
  return true;
}

void ParameterEditor::applyThresholds() {
  if (!state_.worker || state_.staticMap()) return;  // a map file has nothing to rebuild
  auto shown = state_.worker->global();              // taken first: the worker may publish the edit's map at once
  try {
    state_.worker->setThresholds(state_.ui.params.global);
  } catch (const std::exception& e) {
    state_.report(StatusLine::Kind::kError, errorMessage(e));
    return;
  }
  state_.edit_diff.edited(std::move(shown), state_.ui.params.global);
  if (!state_.savedSession()) state_.ui.settings.thresholds = state_.ui.params.global;
}

void ParameterEditor::rerun() {
  if (!state_.worker || state_.savedSession()) return;
  UiState& ui = state_.ui;
  try {
    ui.params.mapper.validate();
  } catch (const std::exception& e) {
    state_.report(StatusLine::Kind::kError, errorMessage(e));
    return;
  }
  state_.worker->rerun(ui.params.mapper);
  ui.settings.mapper = ui.params.mapper;
}

double ParameterEditor::inUse(const Parameter& p) const {
  const UiState& ui = state_.ui;
  if (!state_.worker) return p.get(ui.params);
  ParameterValues used = ui.params;
  if (p.live) {
    const auto global = state_.worker->global();
    if (!global) return p.get(ui.params);
    used.global = global->params;
  } else {
    used.mapper = state_.worker->mapping()->mapper;
  }
  return p.get(used);
}

bool ParameterEditor::pending(const Parameter& p) const { return p.get(state_.ui.params) != inUse(p); }

void ParameterEditor::resetToDefaults() {
  UiState& ui = state_.ui;
  Settings defaults;
  defaults.window_width = ui.settings.window_width;
  defaults.window_height = ui.settings.window_height;
  defaults.last_sequence = ui.settings.last_sequence;
  defaults.recent = ui.settings.recent;  // opening files: a history, not a setting to reset
  const bool saved = state_.savedSession();
  const bool rerun_needed =
      state_.worker && !saved &&
      !(ParameterValues{state_.worker->mapping()->mapper, {}} == ParameterValues{defaults.mapper, {}});
  ui.settings = defaults;
  ui.params.global = defaults.thresholds;
  if (!saved) {                                       // a saved session keeps the parameters it was mapped with
    const PoseSource poses = ui.params.mapper.poses;  // the sequence's, not a setting
    ui.params.mapper = defaults.mapper;
    ui.params.mapper.poses = poses;
  }
  ui.reset_layout = true;
  applyThresholds();
  player_.setFps(ui.settings.play_fps);
  if (rerun_needed) rerun();
}

}  // namespace vdmap::app::gui
