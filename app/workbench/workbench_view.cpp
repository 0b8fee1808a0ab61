// The Workbench's 3-D view: the camera actions (frame, reset, orbit, pan, zoom), the view through a
// keyframe, picking, and the keyframe graph the view draws.
#include "app/workbench/workbench.h"

#include <algorithm>
#include <cmath>

#include "render/map_mirror.h"
#include "render/map_scene.h"
#include "render/scene_lines.h"
#include "render/view_framing.h"

namespace vdmap::app::gui {

int pickEllipsoid(const std::vector<Ellipsoid>& ellipsoids, const render::ViewCamera& view, float x_px, float y_px,
                  float radius_px) {
  const glm::mat4 T_C_W = view.T_C_W;
  int best = -1;
  float best_d2 = radius_px * radius_px, best_z = 0.f;
  for (std::size_t i = 0; i < ellipsoids.size(); ++i) {
    const Eigen::Vector3d& m = ellipsoids[i].mean;
    const glm::vec4 p = T_C_W * glm::vec4(m.x(), m.y(), m.z(), 1.f);
    if (p.z <= view.near_m || p.z >= view.far_m) continue;
    const float du = view.fx * p.x / p.z + view.cx - x_px, dv = view.fy * p.y / p.z + view.cy - y_px;
    const float d2 = du * du + dv * dv;
    if (d2 > radius_px * radius_px) continue;
    // Within a pixel of the best, the nearer one wins (the one drawn in front).
    const bool closer = best < 0 || d2 + 1.f < best_d2 || (d2 <= best_d2 + 1.f && p.z < best_z);
    if (closer) {
      best = static_cast<int>(i);
      best_d2 = std::min(d2, best_d2);
      best_z = p.z;
    }
  }
  return best;
}

render::GraphScene Workbench::graphScene(const MappingSnapshot& mapping) const {
  render::GraphScene scene;
  const bool before = ui_.show_before_optimisation;
  scene.camera = mapping.camera;
  scene.keyframes = mapping.keyframePoses(before);
  for (const CovisibilityEdge& e : mapping.edges) scene.edges.push_back({e.a, e.b, static_cast<float>(e.weight)});
  for (const LoopEvent& e : mapping.loops) scene.loops.push_back({e.loop.from, e.loop.to, 1.f});
  scene.trajectory = mapping.trajectoryWorld(before);
  if (ui_.settings.show_groundtruth) scene.groundtruth = mapping.groundTruthWorld();
  scene.current_keyframe = mapping.current_keyframe;
  scene.selected_keyframe = ui_.selected_keyframe;
  scene.tracked = mapping.mapper.poses == PoseSource::kTrack;
  return scene;
}

// --- picture stream: framing what is drawn ---
render::DrawnBounds Workbench::drawnMap() const {
  const auto global = worker_ ? worker_->global() : nullptr;
  if (!global) return {};
  const render::ViewSpec spec = viewSpecOf(ui_.settings);
  const std::span<const Ellipsoid> map(global->map.ellipsoids);
  const render::HeightFrame frame = heightFrame();
  return render::drawnBounds(map, spec.sigma, spec.draw(), spec.slice, frame, render::frameAxes(map, frame.up));
}

render::FrameBox Workbench::frameBounds(std::size_t* strays) const {
  if (!worker_) return render::FrameBox(render::robustBounds({}));
  const render::DrawnBounds map = drawnMap();
  if (strays) *strays = map.strays;
  // The cameras the view frames (render::frameBounds): keyframes, every mapped frame, the
  // ground truth when shown.
  render::GraphScene cameras;
  const auto mapping = worker_->mapping();  // held: the worker may replace it meanwhile
  cameras.camera = mapping->camera;
  for (const KeyframeInfo& k : mapping->keyframes) cameras.keyframes.push_back(k.T_W_K);
  for (std::size_t i = 0; i < mapping->trajectory.size(); ++i) cameras.trajectory.push_back(mapping->framePose(i));
  if (ui_.settings.show_groundtruth) cameras.groundtruth = mapping->groundTruthWorld();
  return render::frameBounds(map, cameras);
}

void Workbench::frameMap() {
  const auto global = worker_ ? worker_->global() : nullptr;
  framed_generation_ = global ? global->generation : 0;
  const render::FrameBox box = frameBounds(&framed_strays_);
  ui_.camera.up = framingUp();
  ui_.camera.frame(box, static_cast<float>(ui_.view_width) / std::max(1, ui_.view_height));
  ui_.follow_map = true;
  ui_.view_from_keyframe = -1;
}

void Workbench::resetView() {
  const auto global = worker_ ? worker_->global() : nullptr;
  framed_generation_ = global ? global->generation : 0;
  const render::FrameBox box = frameBounds(&framed_strays_);
  ui_.camera = render::defaultOrbit(box, framingUp(), static_cast<float>(ui_.view_width) / std::max(1, ui_.view_height));
  ui_.follow_map = true;
  ui_.view_from_keyframe = -1;
}
// --- end picture stream ---

void Workbench::orbit(float d_yaw, float d_pitch) {
  ui_.follow_map = false;
  ui_.view_from_keyframe = -1;
  ui_.camera.orbit(d_yaw, d_pitch);
}

void Workbench::pan(float dx_px, float dy_px) {
  ui_.follow_map = false;
  ui_.view_from_keyframe = -1;
  // Metres per pixel at the target's distance, so the point under the cursor follows it.
  const float m_per_px = 2.f * ui_.camera.distance_m * std::tan(glm::radians(ui_.camera.fov_y_deg) * 0.5f) /
                         static_cast<float>(std::max(1, ui_.view_height));
  ui_.camera.pan(-dx_px * m_per_px, dy_px * m_per_px);
}

void Workbench::zoom(float wheel_steps) {
  ui_.follow_map = false;
  ui_.view_from_keyframe = -1;
  ui_.camera.dolly(std::pow(0.9f, wheel_steps));
}

glm::vec3 Workbench::upVector() const {
  if (!worker_ || ui_.settings.up_axis != UpAxis::kData) return render::upDirection(ui_.settings.up_axis, {}, {});
  const auto mapping = worker_->mapping();
  const auto global = worker_->global();
  const std::vector<Transform> cameras = mapping->trajectoryWorld();
  return render::upDirection(UpAxis::kData, cameras,
                             global ? std::span<const Ellipsoid>(global->map.ellipsoids) : std::span<const Ellipsoid>());
}

// The up axis framing just used: heightFrame() holds it for the current snapshots, so the data
// up axis (a fit over every camera and the map) is not estimated a second time per framing.
glm::vec3 Workbench::framingUp() const {
  return worker_ && worker_->global() ? heightFrame().up : upVector();
}

ViewportView Workbench::view(int width, int height) const {
  if (worker_ && ui_.view_from_keyframe >= 0) {
    const auto mapping = worker_->mapping();
    if (ui_.view_from_keyframe < static_cast<int>(mapping->keyframes.size())) {
      const PinholeCamera& c = mapping->camera;
      const render::PixelRect r = render::letterbox(width, height, c.width, c.height);
      const Transform& T_W_K = mapping->keyframes[static_cast<std::size_t>(ui_.view_from_keyframe)].T_W_K;
      return {render::ViewCamera::fromPinhole(c, T_W_K, r.width, r.height), r};
    }
  }
  return {ui_.camera.view(width, height), {0, 0, width, height}};
}

void Workbench::pick(float x_px, float y_px, int width, int height) {
  ui_.picked.reset();
  const auto global = worker_ ? worker_->global() : nullptr;
  if (!global) return;
  const ViewportView v = view(width, height);
  const std::vector<Ellipsoid>& shown = *shownMap().ellipsoids;  // what the slice keeps
  const int i = pickEllipsoid(shown, v.camera, x_px - v.image.x, y_px - v.image.y);
  if (i < 0) return;
  ui_.picked = shown[static_cast<std::size_t>(i)];
  ui_.picked_generation = global->generation;
  selectKeyframe(ui_.picked->keyframe, true);  // the keyframe list scrolls to it
}

// --- height slice ---
render::HeightFrame Workbench::heightFrame() const {
  const auto global = worker_ ? worker_->global() : nullptr;
  if (!global) return {};
  const auto mapping = worker_->mapping();
  SliceCache& c = slice_cache_;
  if (c.global != global || c.axis != ui_.settings.up_axis || (c.axis == UpAxis::kData && c.mapping != mapping)) {
    const glm::vec3 up = upVector();
    if (c.global != global || up != c.frame.up) {
      c.frame = render::heightFrame(global->map.ellipsoids, up);
      c.shown = {};
    }
    c.global = global;
    c.mapping = mapping;
    c.axis = ui_.settings.up_axis;
  }
  return c.frame;
}

Workbench::ShownMap Workbench::shownMap() const {
  const auto global = worker_ ? worker_->global() : nullptr;
  if (!global) return {};
  const render::HeightFrame frame = heightFrame();  // clears the selection on a new map or up
  SliceCache& c = slice_cache_;
  const render::HeightSlice& slice = ui_.settings.slice;
  if (!c.shown.ellipsoids || !(slice == c.slice)) {
    c.slice = slice;
    c.shown.serial = ++c.serial;
    c.shown.ellipsoids = slice.on ? std::make_shared<const std::vector<Ellipsoid>>(
                                        render::slicedMap(global->map.ellipsoids, frame, slice))
                                  : std::shared_ptr<const std::vector<Ellipsoid>>(global, &global->map.ellipsoids);
  }
  return c.shown;
}

void Workbench::moveSlice(int direction) {
  render::HeightSlice& s = ui_.settings.slice;
  const float step = static_cast<float>(direction) * (s.hi_m - s.lo_m);
  s.on = true;
  s.lo_m += step;
  s.hi_m += step;
}
// --- end height slice ---

}  // namespace vdmap::app::gui
