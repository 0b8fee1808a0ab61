#include "app/workbench/pose_editor.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include <Eigen/Geometry>

#include "render/legend.h"

namespace vdmap::app::gui {

glm::vec3 rotationToEulerDeg(const Eigen::Matrix3d& R) {
  // R = Rz(yaw) Ry(pitch) Rx(roll): R(2,0) = -sin(pitch), so pitch = asin(-R(2,0)) lies within
  // +-90 degrees; Eigen's eulerAngles would instead keep yaw in [0, 180] and let pitch pass 90.
  constexpr double kDeg = 180.0 / M_PI;
  const double pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  double roll = 0.0, yaw = 0.0;
  if (std::abs(R(2, 0)) < 1.0 - 1e-9) {
    roll = std::atan2(R(2, 1), R(2, 2));
    yaw = std::atan2(R(1, 0), R(0, 0));
  } else {  // gimbal lock: only yaw - roll (or yaw + roll) is defined; roll 0
    yaw = std::atan2(-R(0, 1), R(1, 1));
  }
  return {static_cast<float>(roll * kDeg), static_cast<float>(pitch * kDeg), static_cast<float>(yaw * kDeg)};
}

Eigen::Matrix3d eulerDegToRotation(const glm::vec3& deg) {
  const double k = M_PI / 180.0;
  return (Eigen::AngleAxisd(deg.z * k, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(deg.y * k, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(deg.x * k, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

void PoseEditor::selectKeyframe(int id, bool scroll) {
  UiState& ui = state_.ui;
  ui.selected_keyframe = id;
  ui.scroll_to_selected = scroll && id >= 0;
  if (!state_.worker) return;
  const auto mapping = state_.worker->mapping();
  if (id < 0 || id >= static_cast<int>(mapping->keyframes.size())) ui.selected_keyframe = -1;
  state_.worker->selectKeyframe(ui.selected_keyframe);
  if (ui.selected_keyframe >= 0) showPose(mapping->keyframes[static_cast<std::size_t>(id)].T_W_K);
}

void PoseEditor::preselectKeyframe(int id) {
  if (!state_.worker) return;
  state_.ui.selected_keyframe = id;
  state_.worker->selectKeyframe(id);
}

bool PoseEditor::takeScrollToSelected() { return std::exchange(state_.ui.scroll_to_selected, false); }

void PoseEditor::showPose(const Transform& T_W_K) {
  const Eigen::Vector3d t = T_W_K.translation();
  state_.ui.pose_translation_m = {t.x(), t.y(), t.z()};
  state_.ui.pose_rotation_deg = rotationToEulerDeg(T_W_K.rotation());
  pose_shown_ = T_W_K;
}

void PoseEditor::syncFields() {
  const int id = state_.ui.selected_keyframe;
  if (!state_.worker || id < 0) return;
  const auto mapping = state_.worker->mapping();
  if (id >= static_cast<int>(mapping->keyframes.size())) return;  // not (yet) mapped: no inspector
  if (mapping->pose_edits < pose_edits_sent_) return;  // an edit is on its way: the snapshot is older than the fields
  const Transform& T = mapping->keyframes[static_cast<std::size_t>(id)].T_W_K;
  if (!T.isApprox(pose_shown_, 1e-12)) showPose(T);
}

void PoseEditor::sendPose(int id, const Transform& T_W_K) {
  state_.worker->setKeyframePose(id, T_W_K);
  ++pose_edits_sent_;
}

void PoseEditor::applyEdit() {
  const UiState& ui = state_.ui;
  // Poses are edited on the map as it is, not on the one before the last optimisation.
  if (!state_.worker || ui.selected_keyframe < 0 || ui.show_before_optimisation) return;
  Transform T = Transform::Identity();
  T.linear() = eulerDegToRotation(ui.pose_rotation_deg);
  T.translation() = Eigen::Vector3d(ui.pose_translation_m.x, ui.pose_translation_m.y, ui.pose_translation_m.z);
  sendPose(ui.selected_keyframe, T);
  pose_shown_ = T;  // the snapshot will hold T: no refill once it does
}

void PoseEditor::beginEdit() {
  if (!state_.worker || state_.ui.selected_keyframe < 0) return;
  undo_.emplace_back(state_.ui.selected_keyframe, pose_shown_);
}

bool PoseEditor::undoEdit() {
  if (!state_.worker || undo_.empty()) return false;
  const auto [id, T] = undo_.back();
  undo_.pop_back();
  sendPose(id, T);
  if (id == state_.ui.selected_keyframe) showPose(T);
  state_.report(StatusLine::Kind::kInfo, "pose of K" + std::to_string(id) + " put back");
  return true;
}

bool PoseEditor::canShowBeforeOptimisation() const {
  return state_.worker && !state_.worker->mapping()->keyframes_before.empty();
}

bool PoseEditor::showBeforeOptimisation(bool before) {
  if (before && !canShowBeforeOptimisation()) {
    state_.ui.show_before_optimisation = false;
    // A saved session keeps the poses after its optimisations only.
    state_.report(StatusLine::Kind::kWarning,
                  state_.worker && !state_.worker->mapping()->loops.empty()
                      ? "this map keeps only the poses after its last optimisation: there is no map before it to show"
                      : "no pose-graph optimisation yet: there is no map before one to show");
    return false;
  }
  state_.ui.show_before_optimisation = before;
  if (state_.worker) state_.worker->showBeforeOptimisation(before);
  return true;
}

std::string PoseEditor::beforeOptimisationBanner(const MappingSnapshot& mapping) const {
  if (!state_.ui.show_before_optimisation) return "";
  const LastOptimisation& last = mapping.last_optimisation;
  char text[200];
  if (last.kind == LastOptimisation::Kind::kRefinement) {
    std::snprintf(text, sizeof text, "BEFORE the final refinement (%s, %d pairs, %s; B: after)", last.method.c_str(),
                  last.pairs, render::metresText(last.correction_m).c_str());
    return text;
  }
  const int i = last.kind == LastOptimisation::Kind::kLoop ? last.loop : static_cast<int>(mapping.loops.size()) - 1;
  if (i < 0 || i >= static_cast<int>(mapping.loops.size())) return "BEFORE the last pose-graph optimisation (B: after)";
  const LoopEvent& loop = mapping.loops[static_cast<std::size_t>(i)];
  std::snprintf(text, sizeof text,
                "BEFORE the last pose-graph optimisation (loop at frame %d, correction %s; B: after)", loop.position,
                render::metresText(loop.loop.correction_m).c_str());
  return text;
}

void PoseEditor::sync() {
  // Seeking back or re-running forgets the optimisation: show the map as it is again.
  if (state_.ui.show_before_optimisation && !canShowBeforeOptimisation()) showBeforeOptimisation(false);
  syncFields();
}

void PoseEditor::newSession() {
  pose_edits_sent_ = 0;
  undo_.clear();
}

}  // namespace vdmap::app::gui
