#pragma once
// The 3-D view's camera and what it shows: frame, reset, orbit, pan, zoom, pivot, the view
// through a keyframe, picking, measuring, the height slice, and the view as a view spec.
#include <cstddef>
#include <memory>
#include <optional>
#include <vector>

#include "app/workbench/pose_editor.h"
#include "app/workbench/workbench_state.h"
#include "render/map_mirror.h"
#include "render/view_framing.h"
#include "render/view_spec.h"

namespace vdmap::app::gui {

/// Picks the ellipsoid whose mean projects nearest to pixel (x, y) of `view` within
/// `radius_px`, preferring the nearer one among those within a pixel of the best; -1 if none.
int pickEllipsoid(const std::vector<Ellipsoid>& ellipsoids, const render::ViewCamera& view, float x_px, float y_px,
                  float radius_px = 8.f);

/// The 3-D view's camera in a viewport, and where its image lies in the viewport (all of it,
/// or the letterbox of "view from keyframe").
struct ViewportView {
  render::ViewCamera camera;
  render::PixelRect image;  ///< top-left origin, viewport pixels
};

/// The camera (ui().camera, follow_map, view_from_keyframe) and what the view draws of the open
/// session.
class ViewController {
 public:
  ViewController(WorkbenchState& state, PoseEditor& poses) : state_(state), poses_(poses) {}

  /// Frames the map (and the trajectory) in the 3-D viewport keeping the viewing direction, and
  /// follows the map again (F).
  void frameMap();
  /// The default view of the whole map about the up axis, following the map again (R).
  void resetView();
  /// The user orbits, pans or zooms: the view stops following the map and leaves "view from
  /// keyframe".
  /// A drag turns the view: about the up axis (orbit), or about the image's axes (trackball,
  /// settings.rotation).
  void orbit(float d_yaw, float d_pitch);
  /// Sets settings.rotation; back to orbit, the view is levelled about the up axis again.
  void setRotation(render::Rotation rotation);
  /// Sets settings.projection and the camera's.
  void setProjection(render::Projection projection);
  /// Turns the view to a preset (top, front, side) along the map's horizontal axes, framed.
  void preset(render::ViewPreset preset);
  void pan(float dx_px, float dy_px);
  void zoom(float wheel_steps);
  /// Zooms by `wheel_steps` toward `p` (world): the point under the cursor stays under it.
  void zoomAt(float wheel_steps, const glm::vec3& p);
  /// The point of the target's plane (facing the view) under pixel (x, y) of a width x height
  /// viewport: where zoomAt and pivotAt go when there is no surface under the cursor.
  glm::vec3 targetPlanePoint(float x_px, float y_px, int width, int height) const;
  /// Turns about `p`: the target moves there, the eye stays (double-click, P).
  void pivotAt(const glm::vec3& p);
  /// Frames the trajectory and the ground truth only (T), keeping the direction.
  void frameTrajectories();
  /// The world's up direction for the view: the setting, or estimated from the data.
  glm::vec3 upVector() const;

  /// The 3-D view in a viewport of width x height (framebuffer pixels).
  ViewportView viewport(int width, int height) const;
  /// Click in the 3-D view at (x, y) of a width x height viewport: sets ui().picked and selects
  /// the ellipsoid's keyframe; a click on nothing clears the pick.
  void pick(float x_px, float y_px, int width, int height);
  /// Ctrl+click: the next measuring point (A, then B, then A again). With ui().measure_snap it
  /// snaps to the nearest ellipsoid centre of the global map.
  void addMeasurePoint(const glm::vec3& p);
  /// Metres per pixel of a pose drag: the view's at the selected keyframe's depth, within
  /// 0.1 mm..5 cm.
  float poseDragSpeed() const;
  /// The keyframe graph of `mapping` as the 3-D view draws it now: keyframe poses, covisibility
  /// and loop edges, trajectory (before the last optimisation when ui().show_before_optimisation)
  /// and the ground truth (tracked poses, when the sequence has one and the setting shows it).
  render::GraphScene graphScene(const MappingSnapshot& mapping) const;

  /// The view shown, as a view file holds it (docs/workbench.md "Save view"): container:K while
  /// the container window is open (2W x 2H), keyframe:K while viewing from a keyframe (the
  /// letterbox's size), else the global view with its camera (eye, target, up, field of view) at
  /// the viewport's size; the view options and the selected keyframe from the settings and UI.
  render::ViewSpec spec() const;
  /// Shows `spec` (the inverse of spec(), but the size: the window's viewport stays as laid
  /// out): the view options go into the settings, the camera as given (else the default view,
  /// turned by spec.orbit), and the view stops following the map. Keyframe and container views
  /// select their keyframe (an id not mapped: the global view, and false is returned). The
  /// thresholds stay: a view file's apply only through --settings.
  bool applySpec(const render::ViewSpec& spec);

  /// What the 3-D view draws of the global map, boxed (render::drawnBounds at the settings'
  /// sigma, draw mode and slice): what F frames and the layout self-check projects.
  render::DrawnBounds drawnMap() const;
  /// The strays the last F / R / follow left out of the frame (the hint line counts them).
  std::size_t framedStrays() const { return framed_strays_; }
  /// The global map's height frame about upVector(): heights above its floor colour the map
  /// (colour "height") and bound the slice. Computed once per map and up direction.
  render::HeightFrame heightFrame() const;
  /// What the 3-D view draws and picks of the global map: all of it, or with the settings' slice
  /// on the ellipsoids it keeps (render::slicedMap, as `vdmap render --slice`); while
  /// ui().show_edit_diff shows the last edit's diff, its coloured map (diffColoured) instead of
  /// the map. `serial` is new whenever the selection is (a new map, up direction, slice or
  /// diff). Null while none is open.
  struct ShownMap {
    std::shared_ptr<const std::vector<Ellipsoid>> ellipsoids;
    int serial = 0;
  };
  ShownMap shownMap() const;
  /// The last threshold edit's diff (EditDiffTracker::diff), null when there is none.
  const MapDiff* diff() const { return state_.edit_diff.diff(); }
  /// The diff the view draws (ui().show_edit_diff and a diff of the map shown), else null.
  const MapDiff* shownDiff() const;
  /// PgUp / PgDn: the slice moves up (+1) or down (-1) by its thickness (one floor at a time).
  void moveSlice(int direction);

  /// Once per UI frame: the pick cleared when the map changed, the view re-framed while it
  /// follows the map, and the map hidden while the mesh layer comes on (syncMeshLayer).
  void sync();
  /// A new session is open: the view frames its first map afresh.
  void newSession() { framed_generation_ = -1; }

 private:
  // The box the view frames: drawnMap() (strays left out, so a few far ellipsoids do not shrink
  // the map to a dot), grown to hold every camera of the trajectory and every keyframe's frustum
  // as drawn. `strays` receives drawnMap's count.
  render::FrameBox frameBounds(std::size_t* strays = nullptr) const;
  // upVector(), from heightFrame's cache when it holds it.
  glm::vec3 framingUp() const;
  // The ellipsoids lie on the mesh and cover it, so the mesh layer coming on (ticked, from the
  // settings, or a session opened with it on) hides the map, and going off shows it again unless
  // draw was set meanwhile. A map file has no mesh: the layer is not shown and hides nothing.
  void syncMeshLayer();

  WorkbenchState& state_;
  UiState& ui_ = state_.ui;
  const std::unique_ptr<MappingWorker>& worker_ = state_.worker;
  PoseEditor& poses_;                      // a pick or a keyframe view selects its keyframe
  int framed_generation_ = -1;             // the global map the view was last framed on
  int framed_frames_ = 0;                  // the frames it held (a threshold change keeps them)
  std::pair<int, int> framed_size_{0, 0};  // and the viewport it was framed in
  std::size_t framed_strays_ = 0;          // left out of that frame
  bool framed_mesh_ = false;               // it held the mesh layer's mesh
  bool mesh_shown_ = false;                // the mesh layer was on (with local maps) at the last sync
  bool map_hidden_for_mesh_ = false;       // its coming on hid the map
  // heightFrame's and shownMap's cache, keyed by the global snapshot and the up axis.
  struct SliceCache {
    std::shared_ptr<const GlobalSnapshot> global;
    std::shared_ptr<const MappingSnapshot> mapping;  // its cameras give the data up axis
    UpAxis axis = UpAxis::kData;
    std::optional<glm::vec3> user_up;
    int serial = 0;
    render::HeightFrame frame;
    render::HeightSlice slice;
    int diff_serial = 0;  // the diff shown (0: none)
    ShownMap shown;
  };
  mutable SliceCache slice_cache_;
};

}  // namespace vdmap::app::gui
