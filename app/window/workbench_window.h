#pragma once
// The workbench window: GLFW + Dear ImGui drawing of a Workbench (all logic lives there).
#include <functional>
#include <string>
#include <vector>

#include "app/cli/sequence_args.h"
#include "app/workbench/script_run.h"
#include "app/workbench/workbench.h"

namespace vdmap::app::gui {

/// Work to do before the sequence can be opened (rendering the built-in scene on first start):
/// run on its own thread while the window shows its progress. run() reports (done, total) and
/// returns the folder to open with `args`; it stops soon after cancelled() turns true (the window
/// was closed), throwing and leaving nothing half-written.
struct Preparation {
  std::string what;
  SequenceArgs args;
  std::function<std::string(const std::function<void(std::size_t, std::size_t)>& progress,
                            const std::function<bool()>& cancelled)>
      run;
};

/// Added to a GLFW key code by parseKeyNames for "ctrl+KEY": the key pressed with Ctrl.
inline constexpr int kCtrlKey = 1 << 20;
/// The keys --press takes, by name ("space", "right", "h", "ctrl+s", ...), as GLFW key codes
/// (kCtrlKey added for ctrl+). Throws std::invalid_argument naming the key for an unknown name.
std::vector<int> parseKeyNames(const std::string& comma_separated);

/// Opens the window (and runs `prepare` first when given), runs until it is closed (or the script
/// is done with `exit`). `settings_file`'s folder keeps the window layout (imgui.ini) unless it is
/// empty; the window size goes into bench.ui().settings. Returns the exit code. Throws
/// std::runtime_error when no window can be opened.
int runWorkbenchWindow(Workbench& bench, const ScriptOptions& script, const std::string& settings_file,
                       Preparation prepare = {});

}  // namespace vdmap::app::gui
