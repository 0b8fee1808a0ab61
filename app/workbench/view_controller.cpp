#include "app/workbench/view_controller.h"

#include <algorithm>
#include <cmath>

#include "render/map_scene.h"
#include "render/scene_lines.h"

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

render::GraphScene ViewController::graphScene(const MappingSnapshot& mapping) const {
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

render::DrawnBounds ViewController::drawnMap() const {
  const auto global = worker_ ? worker_->global() : nullptr;
  if (!global) return {};
  const render::ViewSpec spec = viewSpecOf(ui_.settings);
  const std::span<const Ellipsoid> map(global->map.ellipsoids);
  const render::HeightFrame frame = heightFrame();
  render::DrawnBounds drawn =
      render::drawnBounds(map, spec.sigma, spec.draw(), spec.slice, frame, render::frameAxes(map, frame.up));
  if (ui_.settings.show_mesh && global->mesh) render::holdPoints(drawn, global->mesh->positions);  // as render
  return drawn;
}

render::FrameBox ViewController::frameBounds(std::size_t* strays) const {
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

void ViewController::frameMap() {
  const auto global = worker_ ? worker_->global() : nullptr;
  framed_generation_ = global ? global->generation : 0;
  framed_mesh_ = ui_.settings.show_mesh && global && global->mesh;
  framed_frames_ = global ? global->frames_mapped : 0;
  const render::FrameBox box = frameBounds(&framed_strays_);
  if (ui_.settings.rotation == render::Rotation::kOrbit) ui_.camera.up = framingUp();  // a trackball's roll stays
  ui_.camera.orthographic = ui_.settings.projection == render::Projection::kOrthographic;
  ui_.camera.frame(box, static_cast<float>(ui_.view_width) / std::max(1, ui_.view_height));
  ui_.follow_map = true;
  ui_.view_from_keyframe = -1;
}

void ViewController::resetView() {
  const auto global = worker_ ? worker_->global() : nullptr;
  framed_generation_ = global ? global->generation : 0;
  framed_mesh_ = ui_.settings.show_mesh && global && global->mesh;
  framed_frames_ = global ? global->frames_mapped : 0;
  const render::FrameBox box = frameBounds(&framed_strays_);
  ui_.camera = render::defaultOrbit(box, framingUp(), static_cast<float>(ui_.view_width) / std::max(1, ui_.view_height),
                                    render::ViewSpec{}.fov_y_deg, ui_.settings.projection);
  ui_.follow_map = true;
  ui_.view_from_keyframe = -1;
}

void ViewController::orbit(float d_yaw, float d_pitch) {
  ui_.follow_map = false;
  ui_.view_from_keyframe = -1;
  if (ui_.settings.rotation == render::Rotation::kTrackball) ui_.camera.tumble(d_yaw, d_pitch);
  else ui_.camera.orbit(d_yaw, d_pitch);
}

void ViewController::setRotation(render::Rotation rotation) {
  ui_.settings.rotation = rotation;
  // Back to orbiting: level again about the up axis (the trackball's roll undone).
  if (rotation == render::Rotation::kOrbit) {
    const bool ortho = ui_.camera.orthographic;
    ui_.camera = render::OrbitCamera::fromLookAt(ui_.camera.eye(), ui_.camera.target, upVector(), ui_.camera.fov_y_deg);
    ui_.camera.orthographic = ortho;
  }
}

void ViewController::setProjection(render::Projection projection) {
  ui_.settings.projection = projection;
  ui_.camera.orthographic = projection == render::Projection::kOrthographic;
}

void ViewController::preset(render::ViewPreset preset) {
  ui_.follow_map = false;
  ui_.view_from_keyframe = -1;
  const auto global = worker_ ? worker_->global() : nullptr;
  const glm::vec3 up = framingUp();
  const glm::mat3 axes = global ? render::frameAxes(global->map.ellipsoids, up) : render::frameAxes({}, up);
  render::presetView(ui_.camera, preset, axes);
  ui_.camera.frame(frameBounds(), static_cast<float>(ui_.view_width) / std::max(1, ui_.view_height));
}

void ViewController::pan(float dx_px, float dy_px) {
  ui_.follow_map = false;
  ui_.view_from_keyframe = -1;
  // Metres per pixel at the target's distance, so the point under the cursor follows it.
  const float m_per_px = 2.f * ui_.camera.distance_m * std::tan(glm::radians(ui_.camera.fov_y_deg) * 0.5f) /
                         static_cast<float>(std::max(1, ui_.view_height));
  ui_.camera.pan(-dx_px * m_per_px, dy_px * m_per_px);
}

void ViewController::zoom(float wheel_steps) {
  ui_.follow_map = false;
  ui_.view_from_keyframe = -1;
  ui_.camera.dolly(std::pow(0.9f, wheel_steps));
}

void ViewController::zoomAt(float wheel_steps, const glm::vec3& p) {
  ui_.follow_map = false;
  ui_.view_from_keyframe = -1;
  // eye' = (1 - f) p + f eye on the line from the eye to p: p stays at its pixel.
  const float f = std::pow(0.9f, wheel_steps);
  ui_.camera.target += (1.f - f) * (p - ui_.camera.target);
  ui_.camera.distance_m = std::max(1e-3f, ui_.camera.distance_m * f);
}

glm::vec3 ViewController::targetPlanePoint(float x_px, float y_px, int width, int height) const {
  const render::ViewCamera v = ui_.camera.view(width, height);
  const glm::vec4 t = v.T_C_W * glm::vec4(ui_.camera.target, 1.f);
  const float z = t.z > v.near_m ? t.z : ui_.camera.distance_m;
  const glm::vec4 c((x_px - v.cx) / v.fx * z, (y_px - v.cy) / v.fy * z, z, 1.f);
  return glm::vec3(glm::inverse(v.T_C_W) * c);
}

void ViewController::pivotAt(const glm::vec3& p) {
  const glm::vec3 eye = ui_.camera.eye();
  if (glm::length(p - eye) < 1e-4f) return;
  ui_.follow_map = false;
  ui_.view_from_keyframe = -1;
  ui_.camera = render::OrbitCamera::fromLookAt(eye, p, ui_.camera.up, ui_.camera.fov_y_deg);
}

void ViewController::frameTrajectories() {
  const auto mapping = worker_ ? worker_->mapping() : nullptr;
  if (!mapping) return;
  glm::vec3 lo(INFINITY), hi(-INFINITY);
  const auto grow = [&](const std::vector<Transform>& poses) {
    for (const Transform& T : poses) {
      const glm::vec3 p(T.translation().x(), T.translation().y(), T.translation().z());
      lo = glm::min(lo, p);
      hi = glm::max(hi, p);
    }
  };
  grow(mapping->trajectoryWorld(ui_.show_before_optimisation));
  if (ui_.settings.show_groundtruth) grow(mapping->groundTruthWorld());
  if (!(lo.x <= hi.x)) {
    state_.report(StatusLine::Kind::kWarning, "no trajectory yet to frame");
    return;
  }
  const glm::vec3 pad(0.05f);  // a straight path still gets a box
  ui_.camera.frame(lo - pad, hi + pad, static_cast<float>(ui_.view_width) / std::max(1, ui_.view_height));
  ui_.follow_map = false;  // a growing map must not take the view back
  ui_.view_from_keyframe = -1;
}

glm::vec3 ViewController::upVector() const {
  if (ui_.settings.up_vector) return glm::normalize(*ui_.settings.up_vector);
  if (!worker_ || ui_.settings.up_axis != UpAxis::kData) return render::upDirection(ui_.settings.up_axis, {}, {});
  const auto mapping = worker_->mapping();
  const auto global = worker_->global();
  const std::vector<Transform> cameras = mapping->trajectoryWorld();
  return render::upDirection(
      UpAxis::kData, cameras,
      global ? std::span<const Ellipsoid>(global->map.ellipsoids) : std::span<const Ellipsoid>());
}

// The up axis framing just used: heightFrame() holds it for the current snapshots, so the data
// up axis (a fit over every camera and the map) is not estimated a second time per framing.
glm::vec3 ViewController::framingUp() const { return worker_ && worker_->global() ? heightFrame().up : upVector(); }

ViewportView ViewController::viewport(int width, int height) const {
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

void ViewController::pick(float x_px, float y_px, int width, int height) {
  ui_.picked.reset();
  const auto global = worker_ ? worker_->global() : nullptr;
  if (!global) return;
  const ViewportView v = viewport(width, height);
  const std::vector<Ellipsoid>& shown = *shownMap().ellipsoids;  // what the slice keeps
  const int i = pickEllipsoid(shown, v.camera, x_px - v.image.x, y_px - v.image.y);
  if (i < 0) return;
  ui_.picked = shown[static_cast<std::size_t>(i)];
  ui_.picked_generation = global->generation;
  poses_.selectKeyframe(ui_.picked->keyframe, true);  // the keyframe list scrolls to it
}

void ViewController::addMeasurePoint(const glm::vec3& point) {
  glm::vec3 p = point;
  if (ui_.measure_snap)
    if (const auto g = worker_ ? worker_->global() : nullptr; g && !g->map.ellipsoids.empty()) {
      const Eigen::Vector3d q(p.x, p.y, p.z);
      double best = INFINITY;
      for (const Ellipsoid& e : g->map.ellipsoids)
        if (const double d = (e.mean - q).squaredNorm(); d < best) {
          best = d;
          p = {e.mean.x(), e.mean.y(), e.mean.z()};
        }
    }
  if (!ui_.measure_a || ui_.measure_b) {
    ui_.measure_a = p;
    ui_.measure_b.reset();
  } else {
    ui_.measure_b = p;
  }
}

float ViewController::poseDragSpeed() const {
  const render::ViewCamera v = viewport(ui_.view_width, ui_.view_height).camera;
  float depth = ui_.camera.distance_m;
  const auto mapping = worker_ ? worker_->mapping() : nullptr;
  const int id = ui_.selected_keyframe;
  if (mapping && id >= 0 && id < static_cast<int>(mapping->keyframes.size())) {
    const Eigen::Vector3d t = mapping->keyframes[static_cast<std::size_t>(id)].T_W_K.translation();
    const float z = (v.T_C_W * glm::vec4(t.x(), t.y(), t.z(), 1.f)).z;
    if (z > v.near_m) depth = z;
  }
  return std::clamp(depth / std::max(1.f, v.fy), 1e-4f, 0.05f);
}

render::ViewSpec ViewController::spec() const {
  render::ViewSpec spec = viewSpecOf(ui_.settings);
  spec.selected_keyframe = ui_.selected_keyframe;
  spec.fov_y_deg = ui_.camera.fov_y_deg;
  const auto mapping = worker_ ? worker_->mapping() : nullptr;
  const int keyframes = mapping ? static_cast<int>(mapping->keyframes.size()) : 0;
  const auto mapped = [&](int id) { return id >= 0 && id < keyframes; };
  if (ui_.show_container && mapped(ui_.selected_keyframe)) {
    spec.kind = render::ViewKind::kContainer;
    spec.keyframe = ui_.selected_keyframe;
    spec.sigma = kContainerSigma;  // what the container window draws, whatever the 3-D view's sigma
    spec.width = 2 * mapping->camera.width;
    spec.height = 2 * mapping->camera.height;
  } else if (mapped(ui_.view_from_keyframe)) {
    spec.kind = render::ViewKind::kKeyframe;
    spec.keyframe = ui_.view_from_keyframe;
    const render::PixelRect r =
        render::letterbox(ui_.view_width, ui_.view_height, mapping->camera.width, mapping->camera.height);
    spec.width = r.width;
    spec.height = r.height;
  } else {
    spec.width = ui_.view_width;
    spec.height = ui_.view_height;
    spec.look_at = render::LookAt{ui_.camera.eye(), ui_.camera.target, ui_.camera.up, ui_.camera.fov_y_deg};
  }
  return spec;
}

bool ViewController::applySpec(const render::ViewSpec& spec) {
  Settings& s = ui_.settings;
  s.up_axis = spec.up;
  s.up_vector = spec.up_vector;
  s.projection = spec.projection;
  s.rotation = spec.rotation;
  s.color = spec.color;
  s.show_ellipsoids = spec.ellipsoids;
  s.hide_map = spec.map_hidden;
  if (spec.kind != render::ViewKind::kContainer) s.ellipsoid_sigma = spec.sigma;  // a container's is fixed
  s.show_frustums = spec.layers.frustums;
  s.show_graph = spec.layers.graph;
  s.show_trajectory = spec.layers.trajectory;
  s.show_groundtruth = spec.layers.groundtruth;
  s.show_legend = spec.layers.legend;
  s.container_grid = spec.layers.grid;
  s.container_bounds = spec.layers.bounds;
  s.show_mesh = spec.layers.mesh;
  s.mesh_style = spec.mesh_style;
  mesh_shown_ = s.show_mesh && !state_.staticMap();  // the view's draw stands as it says
  map_hidden_for_mesh_ = false;
  s.background = spec.background;
  s.slice = spec.slice;  // height slice
  ui_.show_container = false;
  ui_.view_from_keyframe = -1;
  // The camera as `vdmap render` makes it (render/view_framing.h), at the viewport's aspect.
  render::ViewScene scene;
  scene.bounds = frameBounds();
  scene.up = upVector();
  ui_.camera = render::orbitCamera(spec, scene, ui_.view_width, ui_.view_height);
  framed_generation_ = worker_ && worker_->global() ? worker_->global()->generation : 0;
  framed_frames_ = worker_ && worker_->global() ? worker_->global()->frames_mapped : 0;
  framed_size_ = {ui_.view_width, ui_.view_height};
  ui_.follow_map = !spec.look_at && !spec.orbit;  // "camera": null is the framed view, which follows the map
  const int id = spec.kind == render::ViewKind::kGlobal ? spec.selected_keyframe : spec.keyframe;
  if (id >= 0 || ui_.selected_keyframe >= 0) poses_.selectKeyframe(id);
  if (spec.kind == render::ViewKind::kGlobal) return true;
  if (ui_.selected_keyframe != spec.keyframe) {
    state_.report(StatusLine::Kind::kError, "the view's keyframe " + std::to_string(spec.keyframe) + " is not mapped");
    return false;
  }
  if (spec.kind == render::ViewKind::kKeyframe) ui_.view_from_keyframe = spec.keyframe;
  else ui_.show_container = true;
  return true;
}

render::HeightFrame ViewController::heightFrame() const {
  const auto global = worker_ ? worker_->global() : nullptr;
  if (!global) return {};
  const auto mapping = worker_->mapping();
  SliceCache& c = slice_cache_;
  if (c.global != global || c.axis != ui_.settings.up_axis || c.user_up != ui_.settings.up_vector ||
      (c.axis == UpAxis::kData && c.mapping != mapping)) {
    // The data up axis is estimated again when frames were mapped (or another session or axis
    // is shown), not for a threshold change alone: the view's up, heights and slice stay, so
    // before and after compare.
    const bool same_frames = c.global && c.global->frames_mapped == global->frames_mapped && c.mapping == mapping &&
                             c.axis == ui_.settings.up_axis && c.user_up == ui_.settings.up_vector;
    const glm::vec3 up = same_frames ? c.frame.up : upVector();
    if (c.global != global || up != c.frame.up) {
      c.frame = render::heightFrame(global->map.ellipsoids, up);
      c.shown = {};
    }
    c.global = global;
    c.mapping = mapping;
    c.axis = ui_.settings.up_axis;
    c.user_up = ui_.settings.up_vector;
  }
  return c.frame;
}

ViewController::ShownMap ViewController::shownMap() const {
  const auto global = worker_ ? worker_->global() : nullptr;
  if (!global) return {};
  const render::HeightFrame frame = heightFrame();  // clears the selection on a new map or up
  SliceCache& c = slice_cache_;
  const render::HeightSlice& slice = ui_.settings.slice;
  const MapDiff* diff = shownDiff();
  const int diff_serial = diff ? diff->serial : 0;
  if (!c.shown.ellipsoids || !(slice == c.slice) || diff_serial != c.diff_serial) {
    c.slice = slice;
    c.diff_serial = diff_serial;
    c.shown.serial = ++c.serial;
    const auto map = diff ? std::make_shared<const std::vector<Ellipsoid>>(diffColoured(*diff))
                          : std::shared_ptr<const std::vector<Ellipsoid>>(global, &global->map.ellipsoids);
    c.shown.ellipsoids =
        slice.on ? std::make_shared<const std::vector<Ellipsoid>>(render::slicedMap(*map, frame, slice)) : map;
  }
  return c.shown;
}

const MapDiff* ViewController::shownDiff() const {
  return state_.edit_diff.shown(ui_.show_edit_diff, worker_ ? worker_->global() : nullptr);
}

void ViewController::moveSlice(int direction) {
  render::HeightSlice& s = ui_.settings.slice;
  const float step = static_cast<float>(direction) * (s.hi_m - s.lo_m);
  s.on = true;
  s.lo_m += step;
  s.hi_m += step;
}

void ViewController::syncMeshLayer() {
  const bool shown = ui_.settings.show_mesh && !state_.staticMap();
  if (shown == mesh_shown_) return;
  mesh_shown_ = shown;
  bool& hide = ui_.settings.hide_map;
  if (shown) {
    map_hidden_for_mesh_ = !hide;
    hide = true;
  } else {
    if (map_hidden_for_mesh_) hide = false;
    map_hidden_for_mesh_ = false;
  }
}

void ViewController::sync() {
  syncMeshLayer();
  const auto global = worker_->global();
  const int generation = global ? global->generation : 0;
  if (ui_.picked && ui_.picked_generation != generation) ui_.picked.reset();  // it may not exist in the new map
  // Framed again for a new map, and for a new viewport size (its aspect): the window's panels
  // settle a frame or two after the first map, and a resized window keeps the map framed.
  const std::pair<int, int> size{ui_.view_width, ui_.view_height};
  // Not for a new map of the same frames (a threshold change): the camera stays, so before and
  // after compare.
  const bool grown = generation != framed_generation_ && (!global || global->frames_mapped != framed_frames_);
  // The mesh layer's first mesh, built after the map it was turned on over: framed with it.
  const bool new_mesh = ui_.settings.show_mesh && global && global->mesh && !framed_mesh_;
  if (ui_.follow_map && ui_.view_from_keyframe < 0 &&
      (framed_generation_ < 0 || grown || new_mesh || size != framed_size_) && global &&
      !global->map.ellipsoids.empty()) {
    if (framed_generation_ < 0) resetView();
    else frameMap();
    framed_size_ = size;
  }
}

}  // namespace vdmap::app::gui
