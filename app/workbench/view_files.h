#pragma once
// The view as a file and in memory: view files (docs/workbench.md "Save view") saved and loaded,
// quick views 1..9, and where screenshots go.
#include <array>
#include <ctime>
#include <filesystem>
#include <optional>
#include <string>

#include "app/view/view_file.h"
#include "app/workbench/parameter_editor.h"
#include "app/workbench/view_controller.h"
#include "app/workbench/workbench_state.h"
#include "render/view_spec.h"

namespace vdmap::app::gui {

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

/// Saves and shows the view of the 3-D view (ViewController::spec) as view files and quick views.
class ViewFiles {
 public:
  ViewFiles(WorkbenchState& state, ViewController& view, ParameterEditor& parameters)
      : state_(state), view_(view), parameters_(parameters) {}

  /// Reads `file` (a view file) and shows its view (ViewController::applySpec); with `thresholds`
  /// its thresholds are applied too. A view whose size is not the viewport's warns (the picture
  /// differs from `vdmap render --view-file`). False (the status line says why) on failure.
  bool load(const std::string& file, bool thresholds);
  /// Writes the view shown and the thresholds as a view file to `file`; the status line and
  /// stdout give its absolute path and the `vdmap render` command that draws it. False (the
  /// status line says why) when nothing is open or the file cannot be written.
  bool save(const std::string& file);
  /// As save, but never overwrites silently: the default name (vdmap_view.json) takes the
  /// first free number (vdmap_view-2.json ...); another name that exists is written only with
  /// `replace`, else ui().confirm_view_replace asks and false is returned.
  bool saveSafely(const std::string& file, bool replace = false);
  /// Warns (true) when `asked`'s size is not the viewport's (load, --view-file).
  bool warnAboutSize(const render::ViewSpec& asked);
  /// Ctrl+1..9 keep the view shown; 1..9 show it again (false: none kept there). With
  /// keepQuickViewsIn they are view files there too, so they last beyond the run.
  void storeQuickView(int slot);
  bool recallQuickView(int slot);
  /// Quick views are written to and read from FOLDER/quick_views/N.json ("": in memory only).
  void keepQuickViewsIn(std::filesystem::path folder) { quick_view_folder_ = std::move(folder); }
  /// The file a render command names for the open session: the .vdmap or sequence folder.
  const std::string& source() const { return state_.ui.settings.last_sequence; }
  /// What a printed render command draws to show what the window shows: source(), a sequence's
  /// frames mapped so far and how it was opened (--frames, --camera, --poses, ...), and --set for
  /// each parameter that differs from what `vdmap render` starts with.
  CommandSource commandSource() const;

 private:
  WorkbenchState& state_;
  ViewController& view_;
  ParameterEditor& parameters_;  // load with thresholds applies them
  std::array<std::optional<render::ViewSpec>, 9> quick_views_;
  std::filesystem::path quick_view_folder_;  // keepQuickViewsIn's
  std::filesystem::path quickViewFile(int slot) const;
};

}  // namespace vdmap::app::gui
