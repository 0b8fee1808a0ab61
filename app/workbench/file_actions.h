#pragma once
// Opening and writing files in the workbench (docs/workbench.md "Opening files"): a sequence, a
// saved session, a map file or a view file by what the path holds, dropped paths, the recent
// list; exporting the map, saving the session, loading a corrected trajectory.
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "app/cli/sequence_args.h"
#include "app/workbench/view_controller.h"
#include "app/workbench/workbench_state.h"
#include "mapping/files/map_file.h"

namespace vdmap::app::gui {

/// Replaces the open session (WorkbenchState::worker) with a newly opened one, and writes what
/// the open one holds. Failures go to the status line: a bad file never ends the app.
class FileActions {
 public:
  /// `opened` is called after each successful open, so the other controllers forget the old
  /// session.
  FileActions(WorkbenchState& state, ViewController& view, std::function<void()> opened)
      : state_(state), view_(view), opened_(std::move(opened)) {}

  /// Opens a sequence (replacing the current one). On failure the current one stays, the
  /// message goes to the status line and false is returned.
  /// With tracked poses, its keyframe poses are refined after the last frame as setRefinement says
  /// (args.refine is not looked at: the command line's holds for every sequence of the run).
  bool open(const SequenceArgs& args);
  /// Opens a saved session (.vdmap) the same way: its keyframes and saved thresholds, no player.
  bool openSession(const std::string& file);
  /// Opens whatever `path` holds (detectMapFile): a sequence folder (open), a session
  /// (openSession), a map folder, ellipsoid or point PLY or OctoMap (openMapFile), or a view file
  /// (applied as Load view does: the camera and view options, not its thresholds). On success
  /// the path goes to the front of settings().recent (as every open's does).
  bool openPath(const std::string& path);
  /// Opens a map file as a static map: one mapping snapshot (keyframe poses, edges and
  /// trajectory when the file has them) and one global map, nothing to play, rebuild or edit.
  bool openMapFile(const std::string& path);
  /// The same for a map read already (vdmap gui PATH reads it before the window opens).
  bool openMapFile(std::shared_ptr<const StaticMap> map);
  /// Queues a path dropped on the window (or given by --drop); the next frame opens the queue in
  /// order (openDropped), so a drop never opens in the middle of drawing one.
  void drop(std::string path) { dropped_.push_back(std::move(path)); }
  /// Opens the queued drops (openPath each); returns how many were taken. Once per UI frame.
  int openDropped();

  /// The refinement of tracked keyframe poses after the last frame (nullopt: none) for the
  /// sequences and sessions opened from now on (default: joint, as `vdmap map`).
  void setRefinement(std::optional<MapRefinementParams> refine) { refine_ = std::move(refine); }
  /// The thresholds `file` sets (--settings FILE: a settings.json or a view file, readSettingsArg;
  /// "": none), then the KEY=VALUE of `set` (--set), go over the saved thresholds of every
  /// session opened from now on.
  void setSessionSettings(std::string file, std::vector<std::string> set = {}) {
    session_settings_ = std::move(file);
    session_set_ = std::move(set);
  }
  /// Why the open saved session cannot continue mapping (its player is off), e.g. "mapped to the
  /// end of SEQ (503 of 503 frames): nothing to continue"; "" when it continues or no session is open.
  const std::string& whyPlayerOff() const { return why_player_off_; }
  /// The settings as they are saved: the colour mode the user chose, not the height that a map
  /// file without colours put in place of rgb while it is open.
  Settings savedSettings() const;

  /// Writes what `vdmap map` writes into ui().export_text (on the worker; the outcome shows in
  /// the status line with the absolute path).
  void exportMap();
  /// Saves the session (.vdmap) into ui().session_text (on the worker, like exportMap).
  void saveSession();
  /// Loads ui().trajectory_text, a corrected TUM trajectory: keyframes it names take its poses.
  void loadTrajectory();

 private:
  void opened(const std::string& path);

  WorkbenchState& state_;
  UiState& ui_ = state_.ui;
  std::unique_ptr<MappingWorker>& worker_ = state_.worker;
  ViewController& view_;  // a view file opens as a view
  std::function<void()> opened_;
  std::optional<MapRefinementParams> refine_ = MapRefinementParams{};  // setRefinement's
  std::string session_settings_;                                       // setSessionSettings'
  std::vector<std::string> session_set_;                               // setSessionSettings'
  std::string why_player_off_;                                         // whyPlayerOff()
  std::vector<std::string> dropped_;                                   // drop()'s, not opened yet
  bool height_for_rgb_ = false;  // a map file without colours turned rgb into height (opening another turns it back)
};

}  // namespace vdmap::app::gui
