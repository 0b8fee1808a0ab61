#include "app/gui/workbench.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

#include "mapping/export/map_export.h"

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

glm::vec3 rotationToEulerDeg(const Eigen::Matrix3d& R) {
  const Eigen::Vector3d zyx = R.eulerAngles(2, 1, 0) * (180.0 / M_PI);
  return {static_cast<float>(zyx[2]), static_cast<float>(zyx[1]), static_cast<float>(zyx[0])};
}

Eigen::Matrix3d eulerDegToRotation(const glm::vec3& deg) {
  const double k = M_PI / 180.0;
  return (Eigen::AngleAxisd(deg.z * k, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(deg.y * k, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(deg.x * k, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Workbench::Workbench(Settings settings, std::string warning) {
  ui_.settings = std::move(settings);
  ui_.warning = std::move(warning);
  ui_.sequence_text = ui_.settings.last_sequence;
}

bool Workbench::open(const SequenceArgs& args) {
  try {
    TumSequence sequence = openSequence(args);
    auto session = std::make_unique<MapSession>(std::move(sequence), ui_.settings.mapper, ui_.settings.thresholds);
    session->setFps(ui_.settings.play_fps);
    session_ = std::move(session);  // the old session (if any) stops here
  } catch (const std::exception& e) {
    ui_.error = e.what();
    return false;
  }
  opened(args.folder);
  return true;
}

bool Workbench::openSession(const std::string& file) {
  try {
    Session saved = loadSession(file);
    const GlobalMapParams thresholds = saved.info.global;
    session_ = std::make_unique<MapSession>(std::move(saved), thresholds);
    ui_.settings.thresholds = thresholds;
  } catch (const std::exception& e) {
    ui_.error = e.what();
    return false;
  }
  opened(file);
  return true;
}

bool Workbench::openPath(const std::string& path) {
  const std::filesystem::path p(path);
  if (p.extension() == ".vdmap" && !std::filesystem::is_directory(p)) return openSession(path);
  return open({path, "", "", ""});
}

void Workbench::opened(const std::string& path) {
  ui_.settings.last_sequence = path;
  ui_.sequence_text = path;
  ui_.error.clear();
  ui_.selected_keyframe = ui_.view_from_keyframe = -1;  // as the new session's selection
  ui_.picked.reset();
  ui_.camera_framed = false;
  pose_edits_sent_ = 0;  // a new session has handled none
}

void Workbench::exportMap() {
  if (!session_) return;
  const std::string dir = ui_.export_text;
  session_->withMapper([dir](const Mapper& mapper, const GlobalSnapshot& global) {
    MapExportOptions options;
    options.run_stats = {{"frames", mapper.framesMapped()}, {"source", "vdmap workbench"}};
    vdmap::exportMap(dir, mapper.graph(), global.map, options);
    return "exported the map into " + dir;
  });
}

void Workbench::saveSession() {
  if (!session_) return;
  const std::string file = ui_.session_text;
  session_->withMapper([file](const Mapper& mapper, const GlobalSnapshot& global) {
    SessionInfo info = sessionInfo(mapper, global.params);
    info.frames_mapped = std::max(info.frames_mapped, global.frames_mapped);  // a re-saved session
    vdmap::saveSession(file, mapper.graph(), info);
    return "saved the session to " + file;
  });
}

void Workbench::applyThresholds() {
  if (!session_) return;
  try {
    session_->setThresholds(ui_.settings.thresholds);
  } catch (const std::exception& e) {
    ui_.error = e.what();
  }
}

void Workbench::rerun() {
  if (session_) session_->rerun(ui_.settings.mapper);
}

void Workbench::resetToDefaults() {
  Settings defaults;
  defaults.window_width = ui_.settings.window_width;
  defaults.window_height = ui_.settings.window_height;
  defaults.last_sequence = ui_.settings.last_sequence;
  const bool rerun_needed = session_ && rerunParamsDiffer(ui_.settings, defaults);
  ui_.settings = defaults;
  ui_.reset_layout = true;
  applyThresholds();
  if (session_) session_->setFps(ui_.settings.play_fps);
  if (rerun_needed) rerun();
}

void Workbench::selectKeyframe(int id) {
  ui_.selected_keyframe = id;
  if (!session_) return;
  const auto mapping = session_->mapping();
  if (id < 0 || id >= static_cast<int>(mapping->keyframes.size())) ui_.selected_keyframe = -1;
  session_->selectKeyframe(ui_.selected_keyframe);
  if (ui_.selected_keyframe >= 0) showPose(mapping->keyframes[static_cast<std::size_t>(id)].T_W_K);
}

void Workbench::showPose(const Transform& T_W_K) {
  const Eigen::Vector3d t = T_W_K.translation();
  ui_.pose_translation_m = {t.x(), t.y(), t.z()};
  ui_.pose_rotation_deg = rotationToEulerDeg(T_W_K.rotation());
  pose_shown_ = T_W_K;
}

void Workbench::syncPoseFields() {
  const int id = ui_.selected_keyframe;
  if (!session_ || id < 0) return;
  const auto mapping = session_->mapping();
  if (id >= static_cast<int>(mapping->keyframes.size())) return;  // not (yet) mapped: no inspector
  if (mapping->pose_edits < pose_edits_sent_) return;  // an edit is on its way: the snapshot is older than the fields
  const Transform& T = mapping->keyframes[static_cast<std::size_t>(id)].T_W_K;
  if (!T.isApprox(pose_shown_, 1e-12)) showPose(T);
}

void Workbench::applyPoseEdit() {
  if (!session_ || ui_.selected_keyframe < 0) return;
  Transform T = Transform::Identity();
  T.linear() = eulerDegToRotation(ui_.pose_rotation_deg);
  T.translation() = Eigen::Vector3d(ui_.pose_translation_m.x, ui_.pose_translation_m.y, ui_.pose_translation_m.z);
  session_->setKeyframePose(ui_.selected_keyframe, T);
  pose_shown_ = T;  // the snapshot will hold T: no refill once it does
  ++pose_edits_sent_;
}

void Workbench::loadTrajectory() {
  if (session_) session_->loadTrajectory(ui_.trajectory_text);
}

void Workbench::resetView() {
  ui_.view_from_keyframe = -1;
  std::vector<glm::vec3> points;
  if (session_) {
    if (const auto global = session_->global())
      for (const Ellipsoid& e : global->map.ellipsoids) points.emplace_back(e.mean.x(), e.mean.y(), e.mean.z());
    const auto mapping = session_->mapping();  // held: the worker may replace it meanwhile
    for (const Transform& T : mapping->trajectory)
      points.emplace_back(T.translation().x(), T.translation().y(), T.translation().z());
  }
  const auto [lo, hi] = render::robustBounds(points);
  ui_.camera = render::OrbitCamera::framing(lo, hi);
  ui_.camera_framed = !points.empty();
}

render::ViewCamera Workbench::view(int width, int height) const {
  if (session_ && ui_.view_from_keyframe >= 0) {
    const auto mapping = session_->mapping();
    if (ui_.view_from_keyframe < static_cast<int>(mapping->keyframes.size()))
      return render::ViewCamera::fromPinhole(mapping->camera,
                                             mapping->keyframes[static_cast<std::size_t>(ui_.view_from_keyframe)].T_W_K,
                                             width, height);
  }
  return ui_.camera.view(width, height);
}

void Workbench::pick(float x_px, float y_px, int width, int height) {
  ui_.picked.reset();
  const auto global = session_ ? session_->global() : nullptr;
  if (!global) return;
  const int i = pickEllipsoid(global->map.ellipsoids, view(width, height), x_px, y_px);
  if (i < 0) return;
  ui_.picked = global->map.ellipsoids[static_cast<std::size_t>(i)];
  selectKeyframe(ui_.picked->keyframe);
}

}  // namespace vdmap::app::gui
