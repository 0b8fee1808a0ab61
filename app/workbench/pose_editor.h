#pragma once
// The selected keyframe and its pose: selecting a keyframe fills the pose fields, a drag sends
// them as its corrected pose (with undo), and the map before or after the last pose-graph
// optimisation.
#include <string>
#include <utility>
#include <vector>

#include "app/workbench/workbench_state.h"

namespace vdmap::app::gui {

/// Euler angles (deg, R = Rz Ry Rx) <-> rotation. rotationToEulerDeg gives pitch (y) within
/// [-90, 90] and roll, yaw within (-180, 180]; at +-90 pitch (gimbal lock) roll is 0.
glm::vec3 rotationToEulerDeg(const Eigen::Matrix3d& R);
Eigen::Matrix3d eulerDegToRotation(const glm::vec3& deg);

/// Selection and pose correction of the open session's keyframes (ui().selected_keyframe,
/// ui().pose_*, ui().show_before_optimisation).
class PoseEditor {
 public:
  explicit PoseEditor(WorkbenchState& state) : state_(state) {}

  /// Selects keyframe `id` for the inspector and tells the session (an id not mapped: none).
  /// `scroll`: the keyframe list scrolls to it once (a pick in the view, a loop marker).
  void selectKeyframe(int id, bool scroll = false);
  /// Selects keyframe `id` even when it is not mapped yet (the scripted run's --keyframe): the
  /// inspector shows it once it is. Unlike selectKeyframe, the pose fields are not filled here.
  void preselectKeyframe(int id);
  /// Whether the keyframe list should scroll to the selection now (once per pick or marker).
  bool takeScrollToSelected();

  /// Sends ui().pose_* as the selected keyframe's new pose.
  void applyEdit();
  /// Remembers the selected keyframe's pose before an edit starts (a drag's first frame), so
  /// undoEdit can put it back.
  void beginEdit();
  /// Puts back the pose from before the last edit (returns false when there is none).
  bool undoEdit();
  bool canUndoEdit() const { return !undo_.empty(); }
  /// Refills ui().pose_* when the selected keyframe's pose changed under them (a re-run, a
  /// trajectory file, seeking back, or a keyframe selected before it was mapped), so an edit
  /// starts from the pose shown.
  void syncFields();

  /// Shows the map before the last pose-graph optimisation (true) or after; refused (false
  /// returned, status line says why) when there was no optimisation.
  bool showBeforeOptimisation(bool before);
  /// Whether the open session has had a pose-graph optimisation (the toggle above can act).
  bool canShowBeforeOptimisation() const;
  /// The banner over the view while the map before the last optimisation shows ("" while not).
  std::string beforeOptimisationBanner(const MappingSnapshot& mapping) const;

  /// Once per UI frame: back to the map after the optimisation when there is none any more
  /// (seeking back or re-running forgets it), and the pose fields refilled.
  void sync();
  /// A new session is open: it has handled no edit, and none can be undone.
  void newSession();

 private:
  void showPose(const Transform& T_W_K);
  void sendPose(int id, const Transform& T_W_K);

  WorkbenchState& state_;
  Transform pose_shown_ = Transform::Identity();  // what ui().pose_* were filled from or sent as
  int pose_edits_sent_ = 0;                       // to this session (MappingSnapshot::pose_edits)
  std::vector<std::pair<int, Transform>> undo_;   // (keyframe, pose before the edit)
};

}  // namespace vdmap::app::gui
