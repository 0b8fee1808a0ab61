#pragma once
// The mapping parameters as the sliders edit them: live thresholds sent at once, re-run
// parameters kept until Re-run, what the shown map was made with, and the defaults.
#include <string>

#include "app/workbench/player.h"
#include "app/workbench/workbench_state.h"

namespace vdmap::app::gui {

/// A parameter's tooltip: what it does, its valid values, its default (the row's "def" button
/// puts it back), its `vdmap map` flag and its settings key.
std::string parameterHelp(const Parameter& p);
/// The value of `p` a run without settings starts with (the library's default).
double defaultValue(const Parameter& p);

/// Edits ui().params and sends them to the open session; while a sequence is open they become
/// the user's settings too (a saved session's never do).
class ParameterEditor {
 public:
  ParameterEditor(WorkbenchState& state, Player& player) : state_(state), player_(player) {}

  /// Sets parameter `p` as edited on a slider, checked as everywhere else (a refused value goes
  /// to the status line and false is returned, the edit is dropped). Live ones are applied at
  /// once; re-run ones stay pending until rerun().
  bool edit(const Parameter& p, double value);
  /// `p` alone back to its default, as edit() sets it (the others stay).
  bool resetParameter(const Parameter& p) { return edit(p, defaultValue(p)); }
  /// Sends the edited thresholds (ui().params.global) to the session (a bad value goes to the
  /// status line).
  void applyThresholds();
  /// Re-maps the sequence with the edited re-run parameters (ui().params.mapper).
  void rerun();
  /// Whether `p` as edited is not (yet) what the shown map was made with: a re-run parameter not
  /// re-run, or a threshold whose rebuild has not arrived.
  bool pending(const Parameter& p) const;
  /// The value of `p` the shown map was made with (the slider's value when nothing is pending).
  double inUse(const Parameter& p) const;
  /// Thresholds, re-run parameters and view options back to their defaults (window size, last
  /// sequence and recent files kept); the thresholds are applied and the layout reset.
  void resetToDefaults();

 private:
  WorkbenchState& state_;
  Player& player_;  // the frame rate is a setting too
};

}  // namespace vdmap::app::gui
