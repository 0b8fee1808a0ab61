#pragma once
// The player of the open sequence: play, pause, step, seek and the frame rate, and the session's
// news (its last error and outcome) into the status line.
#include <string>
#include <vector>

#include "app/workbench/workbench_state.h"

namespace vdmap::app::gui {

/// The loop strip's markers (view pixels along the strip, in time order) merged where they lie
/// closer than `min_px`: each cluster's centre and the indices of its markers.
struct MarkerCluster {
  float x = 0;
  std::vector<int> members;
};
std::vector<MarkerCluster> clusterMarkers(const std::vector<float>& positions_px, float min_px);

/// The player's actions on the open session; each does nothing while none is open.
class Player {
 public:
  explicit Player(WorkbenchState& state) : state_(state) {}

  /// The player's state (all default while nothing is open).
  PlayerStatus status() const;
  /// Plays to the end at the fps limit / pauses.
  void play();
  void pause();
  /// Pauses while playing, else plays (Space).
  void playPause();
  /// One frame forward (Right).
  void step();
  /// One frame back (Left), from the frame asked for rather than the one mapped yet, so quick
  /// taps add up; seeking back re-maps from the first frame.
  void stepBack();
  /// Maps up to the next keyframe (K).
  void stepToKeyframe();
  /// Moves the player to frame `frame` (0-based): forward maps up to it, backward re-maps from
  /// the first frame (MappingWorker::seek).
  void seek(int frame);
  /// Sets the playback limit in frames per second (0: as fast as mapping goes) for the open
  /// sequence and the ones opened later (it is a setting).
  void setFps(float fps);

  /// Once per UI frame: the session's new error or outcome into the status line.
  void sync();
  /// A new session is open: none of its news is shown yet.
  void newSession();

 private:
  WorkbenchState& state_;
  std::string shown_error_, shown_message_;  // the session's, already reported
};

}  // namespace vdmap::app::gui
