#pragma once
// A small file browser inside the window (Browse... beside Open): folders first, what each entry
// opens as, a path field that lists what is typed (and filters by a partial name), a sequence or
// map folder opened as a whole. std::filesystem only; mapping/files/map_file.h tells the kinds.
#include <string>
#include <vector>

#include "mapping/files/map_file.h"

namespace vdmap::app::gui {

/// The browser's state (UI thread only).
struct FileBrowser {
  bool open = false;   ///< its window is shown
  std::string path;    ///< the path field: a folder, or a folder and the start of a name
  std::string listed;  ///< the folder `entries` lists ("" : none yet)
  std::vector<FolderEntry> entries;
  std::string error;  ///< why `listed` cannot be listed
  int selected = -1;  ///< index into entries
};

/// Shows the browser at `start` (a path whose folder is listed; "" : the working folder).
void openFileBrowser(FileBrowser& b, const std::string& start);
/// Draws the browser's window while it is open; returns the path the user chose to open (a double
/// click on an entry that opens, or Open), "" otherwise. The browser closes when one is chosen.
/// `double_click`: the left button was double-clicked since the last frame (WindowState).
std::string drawFileBrowser(FileBrowser& b, bool double_click);

}  // namespace vdmap::app::gui
