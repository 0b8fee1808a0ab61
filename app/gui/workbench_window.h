#pragma once
// The workbench window: GLFW + Dear ImGui drawing of a Workbench (all logic lives there).
#include <string>

#include "app/gui/workbench.h"

namespace vdmap::app::gui {

/// The scripted path for tests and documentation screenshots.
struct ScriptOptions {
  bool play_to_end = false;   ///< press Play at start
  int keyframe = -1;          ///< select this keyframe in the inspector before the screenshot
  std::string screenshot;     ///< PNG of the window, taken once mapping and map building are done
  std::string stats_json;     ///< figures (Sigma_e, Sigma_e', t_g, UI frame time) written then too
  bool exit = false;          ///< close the window once the above are written
};

/// Opens the window, runs until it is closed (or the script is done with `exit`), saves the
/// settings to `settings_file` unless empty. Returns the exit code. Throws std::runtime_error
/// when no window can be opened.
int runWorkbenchWindow(Workbench& bench, const ScriptOptions& script, const std::string& settings_file);

}  // namespace vdmap::app::gui
