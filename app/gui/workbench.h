#pragma once
// The workbench's UI state and the actions it triggers, without a window: ImGui code
// (workbench_window.cpp) only edits UiState and calls these actions, so tests drive the same paths.
#include <memory>
#include <optional>
#include <string>

#include "app/commands.h"
#include "app/gui/map_session.h"
#include "app/gui/settings.h"
#include "render/view_camera.h"

namespace vdmap::app::gui {

/// What only the UI edits (besides the persisted settings).
struct UiState {
  Settings settings;
  render::OrbitCamera camera;
  bool camera_framed = false;     ///< the view was framed on a non-empty map once
  int view_from_keyframe = -1;    ///< >= 0: the 3-D view looks through this keyframe
  int selected_keyframe = -1;
  std::optional<Ellipsoid> picked;
  glm::vec3 pose_translation_m{0.f};  ///< the selected keyframe's pose as edited
  glm::vec3 pose_rotation_deg{0.f};   ///< roll (x), pitch (y), yaw (z): R = Rz Ry Rx
  std::string sequence_text;      ///< the "open sequence" field
  std::string trajectory_text;    ///< the "load corrected trajectory" field
  std::string export_text = "vdmap_export";   ///< export folder
  std::string session_text = "map.vdmap";     ///< "save session" file
  std::string error;              ///< shown in a red banner until dismissed
  std::string warning;            ///< e.g. a corrupt settings file
  bool reset_layout = false;      ///< windows go back to their default places next frame
};

/// Picks the ellipsoid whose mean projects nearest to pixel (x, y) of `view` within
/// `radius_px`, preferring the nearer one among those within a pixel of the best; -1 if none.
int pickEllipsoid(const std::vector<Ellipsoid>& ellipsoids, const render::ViewCamera& view, float x_px,
                  float y_px, float radius_px = 8.f);

/// Euler angles (deg, R = Rz Ry Rx) <-> rotation.
glm::vec3 rotationToEulerDeg(const Eigen::Matrix3d& R);
Eigen::Matrix3d eulerDegToRotation(const glm::vec3& deg);

class Workbench {
 public:
  explicit Workbench(Settings settings, std::string warning = {});

  UiState& ui() { return ui_; }
  const UiState& ui() const { return ui_; }
  /// Null while no sequence is open.
  MapSession* session() { return session_.get(); }

  /// Opens a sequence (replacing the current one). On failure the current one stays, the
  /// message goes to ui().error and false is returned: a bad folder never ends the app.
  bool open(const SequenceArgs& args);
  /// Opens a saved session (.vdmap) the same way: its keyframes and saved thresholds, no player.
  bool openSession(const std::string& file);
  /// Opens `path` as a session when it is a .vdmap file, else as a sequence folder.
  bool openPath(const std::string& path);
  /// Writes what `vdmap map` writes into ui().export_text (on the worker; the outcome shows in
  /// the session status).
  void exportMap();
  /// Saves the session (.vdmap) into ui().session_text (on the worker, like exportMap).
  void saveSession();
  /// Sends the edited thresholds to the session (a bad value goes to ui().error).
  void applyThresholds();
  /// Re-maps the sequence with the edited re-run parameters.
  void rerun();
  /// Thresholds, re-run parameters and view options back to their defaults (window size and
  /// last sequence kept); the thresholds are applied and the layout reset.
  void resetToDefaults();
  /// Selects keyframe `id` for the inspector and tells the session (an id not mapped: none).
  void selectKeyframe(int id);
  /// Sends ui().pose_* as the selected keyframe's new pose.
  void applyPoseEdit();
  /// Once per UI frame: refills ui().pose_* when the selected keyframe's pose changed under them
  /// (a re-run, a trajectory file, seeking back, or a keyframe selected before it was mapped), so
  /// an edit starts from the pose shown.
  void syncPoseFields();
  void loadTrajectory();
  /// Frames the current global map (or the trajectory) and leaves "view from keyframe".
  void resetView();
  /// The 3-D view's camera for a viewport of width x height.
  render::ViewCamera view(int width, int height) const;
  /// Click in the 3-D view at (x, y) of a width x height viewport: sets ui().picked and selects
  /// the ellipsoid's keyframe; a click on nothing clears the pick.
  void pick(float x_px, float y_px, int width, int height);

 private:
  void opened(const std::string& path);
  void showPose(const Transform& T_W_K);

  UiState ui_;
  Transform pose_shown_ = Transform::Identity();  // what ui().pose_* were filled from or sent as
  int pose_edits_sent_ = 0;                        // to this session (MappingSnapshot::pose_edits)
  std::unique_ptr<MapSession> session_;
};

}  // namespace vdmap::app::gui
