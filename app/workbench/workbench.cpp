#include "app/workbench/workbench.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <optional>
#include <utility>

#include <Eigen/Geometry>

#include "app/cli/provenance.h"
#include "app/view/view_file.h"
#include "mapping/files/map_export.h"
#include "render/legend.h"
#include "render/view_framing.h"

namespace vdmap::app::gui {
namespace fs = std::filesystem;
namespace {

std::string absolute(const std::string& path) {
  if (path.empty()) return path;
  std::error_code ignored;
  const fs::path p = fs::absolute(path, ignored);
  return (p.empty() ? fs::path(path) : p).lexically_normal().string();
}

}  // namespace

const std::vector<std::pair<const char*, const char*>>& keyHelp() {
  static const std::vector<std::pair<const char*, const char*>> keys = {
      {"Space", "play / pause"},
      {"Right / Left", "one frame forward / back (taps add up, none is lost; back re-maps from the start)"},
      {"K", "map to the next keyframe"},
      {"F", "frame the map and the cameras (keeps the direction; the view follows the map again)"},
      {"R", "reset the view (default direction about the up axis)"},
      {"V", "view from the selected keyframe (its own intrinsics, letterboxed)"},
      {"C", "the selected keyframe's container view, large (zoom, cell grid, image bounds)"},
      {"B", "tracked poses: the map before / after the last pose-graph optimisation (loop closure)"},
      {"S", "save the view as a view file (View section) and print the `vdmap render` command that draws it"},
      {"T", "frame the trajectories (tracked and ground truth) only"},
      {"PgUp / PgDn", "move the height slice up / down by its thickness (one floor)"},
      {"P, double-click", "turn about the point under the cursor (the eye stays)"},
      {"Q", "probe under the cursor: free / occupied / unknown, distance (Alt+wheel: offset)"},
      {"Ctrl+1..9 / 1..9", "keep the view in quick view 1..9 / show it again (this run only)"},
      {"Ctrl+click", "measure: point A, then B (the distance shows in the view and the Measure section)"},
      {"H, F1", "show or hide these keys"},
      {"Esc", "close the help and the container view, leave \"view from keyframe\""},
      {"Ctrl+Z", "undo the last pose edit"},
      {"left drag", "orbit about the up axis"},
      {"right / middle drag, Shift + left drag", "pan"},
      {"wheel", "zoom toward the point under the cursor"},
      {"click", "pick an ellipsoid (marked magenta; its keyframe is selected)"},
      {"container view: wheel, drag", "zoom, pan"},
  };
  return keys;
}

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

Workbench::Workbench(Settings settings, std::string warning) {
  ui_.settings = std::move(settings);
  ui_.sequence_text = ui_.settings.last_sequence;
  if (!warning.empty()) report(StatusLine::Kind::kWarning, std::move(warning));
}

void Workbench::report(StatusLine::Kind kind, std::string text) {
  if (kind == StatusLine::Kind::kError && first_error_.empty()) first_error_ = text;
  ui_.status = {kind, std::move(text), ui_.status.serial + 1};
}

bool Workbench::open(const SequenceArgs& args) {
  SequenceArgs absolute_args = args;
  absolute_args.folder = absolute(args.folder);
  try {
    TumSequence sequence = openSequence(absolute_args);
    // The pose source belongs to the sequence (--poses, or whether it has ground truth), not
    // to the settings; re-runs keep it.
    MapperParams mapper = ui_.settings.mapper;
    mapper.poses = poseSource(absolute_args, sequence);
    auto worker = std::make_unique<MappingWorker>(std::move(sequence), mapper, ui_.settings.thresholds, refine_);
    worker->setOnChange(on_change_);
    worker->setFps(ui_.settings.play_fps);
    worker_ = std::move(worker);  // the old session (if any) stops here
    ui_.params = {mapper, ui_.settings.thresholds};
    why_player_off_.clear();
  } catch (const std::exception& e) {
    report(StatusLine::Kind::kError, e.what());
    return false;
  }
  opened(absolute_args.folder);
  return true;
}

namespace {

// The frames of a saved session's sequence after its last one, for the player to continue
// with: none when the session cannot continue, its folder is gone, or its camera is not the
// session's. *off says why there are none (the Sequence panel shows it); *why too when it is
// worth a warning (not for a session mapped to its sequence's end).
std::optional<TumSequence> framesAfter(const Session& saved, std::string* off, std::string* why) {
  const SessionInfo& info = saved.info;
  if (info.sequence.empty() || info.state.frames_mapped == 0) {
    *off = "the session names no sequence to continue with";
    return std::nullopt;
  }
  if (info.state.current_keyframe < 0) {
    *off = *why = "the session (format 1) cannot continue mapping: the player is off";
    return std::nullopt;
  }
  try {
    // A session mapped to the end of its sequence has nothing to continue with: no warning.
    if (std::filesystem::is_directory(info.sequence)) {
      const std::size_t listed = TumSequence::open(info.sequence).listedDepthFrames();
      if (listed <= static_cast<std::size_t>(info.state.last_frame_index) + 1) {
        *off = "mapped to the end of " + info.sequence + " (" + std::to_string(info.state.last_frame_index + 1) +
               " of " + std::to_string(listed) + " frames): nothing to continue";
        return std::nullopt;
      }
    }
    SequenceOptions options;
    options.frames.first = info.state.last_frame_index + 1;
    TumSequence rest = TumSequence::open(info.sequence, options);
    if (!(rest.camera() == info.camera))
      throw std::invalid_argument("its camera is not the session's");
    return rest;
  } catch (const std::exception& e) {
    *off = *why = "the player is off: the session's sequence " + info.sequence + " has no frames to continue with (" +
                  e.what() + ")";
    return std::nullopt;
  }
}

// The frames of a session's sequence, for their ground truth, when it was mapped with tracked
// poses and its folder has ground truth; none otherwise (the tracking error then stays hidden).
std::vector<FrameEntry> groundTruthOf(const SessionInfo& info) {
  if (info.mapper.poses != PoseSource::kTrack || !std::filesystem::is_directory(info.sequence)) return {};
  try {
    const TumSequence seq = TumSequence::open(info.sequence);
    if (seq.hasGroundTruth()) return seq.entries();
  } catch (const std::exception&) {  // framesAfter says what is wrong with the folder
  }
  return {};
}

}  // namespace

bool Workbench::openSession(const std::string& file) {
  const std::string path = absolute(file);
  std::string why;
  try {
    Session saved = loadSession(path);
    // The session's own parameters, shown and used; the user's settings stay as they are.
    ParameterValues params{saved.info.mapper, saved.info.global};
    if (!session_settings_.empty()) {  // keys the file lacks keep the session's values
      Settings base;
      base.thresholds = params.global;
      params.global = readSettingsArg(session_settings_, base).thresholds;
    }
    std::string off;
    std::optional<TumSequence> rest = framesAfter(saved, &off, &why);
    std::vector<FrameEntry> truth = groundTruthOf(saved.info);
    auto worker =
        std::make_unique<MappingWorker>(std::move(saved), params.global, std::move(rest), refine_, std::move(truth));
    worker->setOnChange(on_change_);
    worker_ = std::move(worker);
    ui_.params = params;
    why_player_off_ = off;
  } catch (const std::exception& e) {
    report(StatusLine::Kind::kError, e.what());
    return false;
  }
  opened(path);
  if (!why.empty()) report(StatusLine::Kind::kWarning, why);
  return true;
}

// openPath: workbench_files.cpp (opening files of every kind).

void Workbench::opened(const std::string& path) {
  ++session_serial_;
  ui_.settings.last_sequence = path;
  ui_.sequence_text = path;
  report(StatusLine::Kind::kSuccess, "opened " + path);
  ui_.selected_keyframe = ui_.view_from_keyframe = -1;  // as the new session's selection
  ui_.picked.reset();
  ui_.follow_map = true;
  ui_.show_before_optimisation = false;  // as the new session's
  framed_generation_ = -1;
  pose_edits_sent_ = 0;  // a new session has handled none
  pose_undo_.clear();
  shown_error_.clear();
  shown_message_.clear();
}

void Workbench::exportMap() {
  if (!worker_) return;
  const std::string dir = absolute(ui_.export_text);
  // What `vdmap map` writes, for the frames mapped so far: the trajectory and how the map was
  // made (provenance.h). The sequence outlives the worker's commands.
  const TumSequence* seq = worker_->sequence();
  const std::string session = seq ? "" : ui_.settings.last_sequence;  // the .vdmap file opened
  worker_->withMapper([dir, seq, session, refine = refine_](const Mapper& mapper, const GlobalSnapshot& global) {
    MapExportOptions options;
    options.trajectory = mapper.trajectory();
    options.run_stats = {{"frames", mapper.framesMapped()}, {"source", "vdmap workbench"}};
    if (seq) {
      // The range the player has reached: from the sequence's first frame to the last one mapped.
      const int last = mapper.state().last_frame_index;
      options.run_stats["frame_range"] = frameRangeText({seq->frameRange().first, std::max(last + 1, seq->frameRange().first)});
      options.run_stats.update(frameCounts(*seq));
      options.run_stats.erase("frames_mapped");  // of the whole range, which the player may not have reached
    }
    options.run_stats.update(provenanceStats({seq ? seq->folder().string() : std::string(),
                                              seq ? seq->cameraSource() : "session " + session, mapper.camera(),
                                              mapper.params().poses, refine, {mapper.params(), global.params}}));
    vdmap::exportMap(dir, mapper.graph(), global.map, options);
    return "exported the map into " + dir;
  });
}

void Workbench::saveSession() {
  if (!worker_) return;
  const std::string file = absolute(ui_.session_text);
  // The session remembers its sequence, so that it can be continued (vdmap map --load, Open).
  const std::string folder = worker_->sequenceFolder();
  worker_->withMapper([file, folder](const Mapper& mapper, const GlobalSnapshot& global) {
    vdmap::saveSession(file, mapper.graph(), sessionInfo(mapper, global.params, folder));
    return "saved the session to " + file;
  });
}

void Workbench::applyThresholds() {
  if (!worker_ || staticMap()) return;  // a map file has nothing to rebuild (opening files)
  try {
    worker_->setThresholds(ui_.params.global);
  } catch (const std::exception& e) {
    report(StatusLine::Kind::kError, e.what());
    return;
  }
  if (!savedSession()) ui_.settings.thresholds = ui_.params.global;
}

void Workbench::rerun() {
  if (!worker_ || savedSession()) return;
  try {
    ui_.params.mapper.validate();
  } catch (const std::exception& e) {
    report(StatusLine::Kind::kError, e.what());
    return;
  }
  worker_->rerun(ui_.params.mapper);
  ui_.settings.mapper = ui_.params.mapper;
}

bool Workbench::editParameter(const Parameter& p, double value) {
  ParameterValues edited = ui_.params;
  try {
    checkValue(p, value);
    p.set(edited, value);
    validate(edited);
  } catch (const std::exception& e) {
    report(StatusLine::Kind::kError, e.what());
    return false;
  }
  ui_.params = edited;
  if (p.live) applyThresholds();
  return true;
}

double Workbench::inUse(const Parameter& p) const {
  if (!worker_) return p.get(ui_.params);
  ParameterValues used = ui_.params;
  if (p.live) {
    const auto global = worker_->global();
    if (!global) return p.get(ui_.params);
    used.global = global->params;
  } else {
    used.mapper = worker_->mapping()->mapper;
  }
  return p.get(used);
}

bool Workbench::pending(const Parameter& p) const { return p.get(ui_.params) != inUse(p); }

void Workbench::resetToDefaults() {
  Settings defaults;
  defaults.window_width = ui_.settings.window_width;
  defaults.window_height = ui_.settings.window_height;
  defaults.last_sequence = ui_.settings.last_sequence;
  defaults.recent = ui_.settings.recent;  // opening files: a history, not a setting to reset
  const bool rerun_needed = worker_ && !savedSession() && !(ParameterValues{worker_->mapping()->mapper, {}} ==
                                                              ParameterValues{defaults.mapper, {}});
  ui_.settings = defaults;
  ui_.params.global = defaults.thresholds;
  if (!savedSession()) {  // a saved session keeps the parameters it was mapped with
    const PoseSource poses = ui_.params.mapper.poses;  // the sequence's, not a setting
    ui_.params.mapper = defaults.mapper;
    ui_.params.mapper.poses = poses;
  }
  ui_.reset_layout = true;
  applyThresholds();
  setFps(ui_.settings.play_fps);
  if (rerun_needed) rerun();
}

std::shared_ptr<const MappingSnapshot> Workbench::mapping() const { return worker_ ? worker_->mapping() : nullptr; }

std::shared_ptr<const GlobalSnapshot> Workbench::global() const { return worker_ ? worker_->global() : nullptr; }

std::shared_ptr<const SelectionSnapshot> Workbench::selection() const {
  return worker_ ? worker_->selection() : nullptr;
}

PlayerStatus Workbench::player() const { return worker_ ? worker_->status() : PlayerStatus{}; }

void Workbench::play() {
  if (worker_) worker_->play();
}

void Workbench::pause() {
  if (worker_) worker_->pause();
}

void Workbench::seek(int frame) {
  if (worker_) worker_->seek(frame);
}

void Workbench::setFps(float fps) {
  ui_.settings.play_fps = fps;
  if (worker_) worker_->setFps(fps);
}

void Workbench::preselectKeyframe(int id) {
  if (!worker_) return;
  ui_.selected_keyframe = id;
  worker_->selectKeyframe(id);
}

void Workbench::setOnChange(std::function<void()> on_change) {
  on_change_ = std::move(on_change);
  if (worker_) worker_->setOnChange(on_change_);
}

void Workbench::selectKeyframe(int id, bool scroll) {
  ui_.selected_keyframe = id;
  ui_.scroll_to_selected = scroll && id >= 0;
  if (!worker_) return;
  const auto mapping = worker_->mapping();
  if (id < 0 || id >= static_cast<int>(mapping->keyframes.size())) ui_.selected_keyframe = -1;
  worker_->selectKeyframe(ui_.selected_keyframe);
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
  if (!worker_ || id < 0) return;
  const auto mapping = worker_->mapping();
  if (id >= static_cast<int>(mapping->keyframes.size())) return;  // not (yet) mapped: no inspector
  if (mapping->pose_edits < pose_edits_sent_) return;  // an edit is on its way: the snapshot is older than the fields
  const Transform& T = mapping->keyframes[static_cast<std::size_t>(id)].T_W_K;
  if (!T.isApprox(pose_shown_, 1e-12)) showPose(T);
}

void Workbench::sendPose(int id, const Transform& T_W_K) {
  worker_->setKeyframePose(id, T_W_K);
  ++pose_edits_sent_;
}

void Workbench::applyPoseEdit() {
  // Poses are edited on the map as it is, not on the one before the last optimisation.
  if (!worker_ || ui_.selected_keyframe < 0 || ui_.show_before_optimisation) return;
  Transform T = Transform::Identity();
  T.linear() = eulerDegToRotation(ui_.pose_rotation_deg);
  T.translation() = Eigen::Vector3d(ui_.pose_translation_m.x, ui_.pose_translation_m.y, ui_.pose_translation_m.z);
  sendPose(ui_.selected_keyframe, T);
  pose_shown_ = T;  // the snapshot will hold T: no refill once it does
}

void Workbench::beginPoseEdit() {
  if (!worker_ || ui_.selected_keyframe < 0) return;
  pose_undo_.emplace_back(ui_.selected_keyframe, pose_shown_);
}

bool Workbench::undoPoseEdit() {
  if (!worker_ || pose_undo_.empty()) return false;
  const auto [id, T] = pose_undo_.back();
  pose_undo_.pop_back();
  sendPose(id, T);
  if (id == ui_.selected_keyframe) showPose(T);
  report(StatusLine::Kind::kInfo, "pose of K" + std::to_string(id) + " put back");
  return true;
}

void Workbench::loadTrajectory() {
  if (worker_) worker_->loadTrajectory(absolute(ui_.trajectory_text));
}

bool Workbench::canShowBeforeOptimisation() const {
  return worker_ && !worker_->mapping()->keyframes_before.empty();
}

bool Workbench::showBeforeOptimisation(bool before) {
  if (before && !canShowBeforeOptimisation()) {
    ui_.show_before_optimisation = false;
    // A saved session keeps the poses after its optimisations only.
    report(StatusLine::Kind::kWarning, worker_ && !worker_->mapping()->loops.empty()
                                           ? "this map keeps only the poses after its last optimisation: there is no "
                                             "map before it to show"
                                           : "no pose-graph optimisation yet: there is no map before one to show");
    return false;
  }
  ui_.show_before_optimisation = before;
  if (worker_) worker_->showBeforeOptimisation(before);
  return true;
}

void Workbench::sync() {
  if (!worker_) return;
  syncQueries();  // point queries: wanted by the probe or the slice, the slice's computation
  // Seeking back or re-running forgets the optimisation: show the map as it is again.
  if (ui_.show_before_optimisation && !canShowBeforeOptimisation()) showBeforeOptimisation(false);
  syncPoseFields();
  const PlayerStatus st = worker_->status();
  if (st.error != shown_error_) {
    shown_error_ = st.error;
    if (!st.error.empty()) report(StatusLine::Kind::kError, st.error);
  }
  if (st.message != shown_message_) {
    shown_message_ = st.message;
    if (!st.message.empty()) report(StatusLine::Kind::kSuccess, st.message);
  }
  const auto global = worker_->global();
  const int generation = global ? global->generation : 0;
  if (ui_.picked && ui_.picked_generation != generation) ui_.picked.reset();  // it may not exist in the new map
  // Framed again for a new map, and for a new viewport size (its aspect): the window's panels
  // settle a frame or two after the first map, and a resized window keeps the map framed.
  const std::pair<int, int> size{ui_.view_width, ui_.view_height};
  if (ui_.follow_map && ui_.view_from_keyframe < 0 && (generation != framed_generation_ || size != framed_size_) &&
      global && !global->map.ellipsoids.empty()) {
    if (framed_generation_ < 0) resetView();
    else frameMap();
    framed_size_ = size;
  }
}

void Workbench::key(KeyAction action) {
  MappingWorker* s = worker_.get();
  switch (action) {
    case KeyAction::kPlayPause:
      player().playing ? pause() : play();
      break;
    case KeyAction::kStepForward:
      if (s) s->step();
      break;
    case KeyAction::kStepBack:
      // From the frame asked for (not the one mapped yet), so quick taps add up.
      if (const int target = player().target; target >= 2) seek(target - 2);
      break;
    case KeyAction::kNextKeyframe:
      if (s) s->stepToKeyframe();
      break;
    case KeyAction::kFrameMap: frameMap(); break;
    case KeyAction::kResetView: resetView(); break;
    case KeyAction::kViewFromKeyframe:
      if (ui_.selected_keyframe >= 0) ui_.view_from_keyframe = ui_.view_from_keyframe >= 0 ? -1 : ui_.selected_keyframe;
      break;
    case KeyAction::kContainer:  // a map file has no containers (opening files)
      if (!staticMap()) ui_.show_container = !ui_.show_container;
      break;
    case KeyAction::kHelp: ui_.show_help = !ui_.show_help; break;
    case KeyAction::kEscape:
      ui_.show_help = ui_.show_container = false;
      ui_.view_from_keyframe = -1;
      break;
    case KeyAction::kUndo: undoPoseEdit(); break;
    case KeyAction::kBeforeOptimisation: showBeforeOptimisation(!ui_.show_before_optimisation); break;
    case KeyAction::kSaveView: saveViewSafely(ui_.view_file_text); break;
    case KeyAction::kFrameTrajectories: frameTrajectories(); break;
    case KeyAction::kPivotHere: ui_.pivot_requested = true; break;  // the window probes the point under the cursor
    case KeyAction::kSliceUp: moveSlice(1); break;
    case KeyAction::kSliceDown: moveSlice(-1); break;
    case KeyAction::kProbe: ui_.probe = !ui_.probe; break;
  }
}

render::ViewSpec Workbench::viewSpec() const {
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
    const render::PixelRect r = render::letterbox(ui_.view_width, ui_.view_height, mapping->camera.width, mapping->camera.height);
    spec.width = r.width;
    spec.height = r.height;
  } else {
    spec.width = ui_.view_width;
    spec.height = ui_.view_height;
    spec.look_at = render::LookAt{ui_.camera.eye(), ui_.camera.target, ui_.camera.up, ui_.camera.fov_y_deg};
  }
  return spec;
}

bool Workbench::applyViewSpec(const render::ViewSpec& spec) {
  Settings& s = ui_.settings;
  s.up_axis = spec.up;
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
  framed_size_ = {ui_.view_width, ui_.view_height};
  ui_.follow_map = !spec.look_at && !spec.orbit;  // "camera": null is the framed view, which follows the map
  const int id = spec.kind == render::ViewKind::kGlobal ? spec.selected_keyframe : spec.keyframe;
  if (id >= 0 || ui_.selected_keyframe >= 0) selectKeyframe(id);
  if (spec.kind == render::ViewKind::kGlobal) return true;
  if (ui_.selected_keyframe != spec.keyframe) {
    report(StatusLine::Kind::kError, "the view's keyframe " + std::to_string(spec.keyframe) + " is not mapped");
    return false;
  }
  if (spec.kind == render::ViewKind::kKeyframe) ui_.view_from_keyframe = spec.keyframe;
  else ui_.show_container = true;
  return true;
}

bool Workbench::saveView(const std::string& file) {
  if (!worker_) {
    report(StatusLine::Kind::kError, "Save view: nothing is open");
    return false;
  }
  const std::string path = absolute(file);
  try {
    if (path.empty()) throw std::invalid_argument("Save view: type a file name first");
    writeViewFile(path, viewSpec(), ui_.params.global, viewSource());
  } catch (const std::exception& e) {
    report(StatusLine::Kind::kError, e.what());
    return false;
  }
  const std::string command = renderCommand(viewSpec(), viewSource(), path);
  std::cout << "vdmap: view saved to " << path << "; draw it with: " << command << std::endl;
  report(StatusLine::Kind::kSuccess, "view saved to " + path + "; " + command);
  return true;
}

}  // namespace vdmap::app::gui

// ---- The view tools: pick marker list scroll, zoom at the cursor, pivot, pose drag speed,
// measuring, view files and quick views, screenshot names.
namespace vdmap::app::gui {

std::vector<MarkerCluster> clusterMarkers(const std::vector<float>& positions_px, float min_px) {
  std::vector<MarkerCluster> out;
  float first = 0.f;  // the cluster's first marker: a cluster spans at most min_px
  for (std::size_t i = 0; i < positions_px.size(); ++i) {
    const float x = positions_px[i];
    if (out.empty() || x - first >= min_px) {
      out.push_back({x, {}});
      first = x;
    }
    MarkerCluster& c = out.back();
    c.members.push_back(static_cast<int>(i));
    c.x = 0.5f * (first + x);
  }
  return out;
}

fs::path screenshotFolder() {
  const char* pictures = std::getenv("XDG_PICTURES_DIR");
  if (pictures && *pictures) return fs::path(pictures) / "vdmap";
  const char* home = std::getenv("HOME");
  if (home && *home) return fs::path(home) / "Pictures" / "vdmap";
  return {};
}

fs::path freeTimestampedName(const fs::path& folder, std::time_t when, const std::string& stem) {
  std::tm local{};
  localtime_r(&when, &local);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", &local);
  return freeNumberedName(folder / (stem + "-" + stamp + ".png"));
}

fs::path defaultScreenshotFile(std::time_t when) {
  fs::path folder = screenshotFolder();
  std::error_code error;
  if (!folder.empty()) fs::create_directories(folder, error);
  if (folder.empty() || error) folder = fs::current_path(error);
  return freeTimestampedName(folder, when);
}

fs::path freeNumberedName(const fs::path& file) {
  std::error_code ignored;
  if (!fs::exists(file, ignored)) return file;
  const fs::path stem = file.parent_path() / file.stem();
  for (int n = 2;; ++n) {
    fs::path next = stem;
    next += "-" + std::to_string(n) + file.extension().string();
    if (!fs::exists(next, ignored)) return next;
  }
}

void Workbench::zoomAt(float wheel_steps, const glm::vec3& p) {
  ui_.follow_map = false;
  ui_.view_from_keyframe = -1;
  // eye' = (1 - f) p + f eye on the line from the eye to p: p stays at its pixel.
  const float f = std::pow(0.9f, wheel_steps);
  ui_.camera.target += (1.f - f) * (p - ui_.camera.target);
  ui_.camera.distance_m = std::max(1e-3f, ui_.camera.distance_m * f);
}

glm::vec3 Workbench::targetPlanePoint(float x_px, float y_px, int width, int height) const {
  const render::ViewCamera v = ui_.camera.view(width, height);
  const glm::vec4 t = v.T_C_W * glm::vec4(ui_.camera.target, 1.f);
  const float z = t.z > v.near_m ? t.z : ui_.camera.distance_m;
  const glm::vec4 c((x_px - v.cx) / v.fx * z, (y_px - v.cy) / v.fy * z, z, 1.f);
  return glm::vec3(glm::inverse(v.T_C_W) * c);
}

void Workbench::pivotAt(const glm::vec3& p) {
  const glm::vec3 eye = ui_.camera.eye();
  if (glm::length(p - eye) < 1e-4f) return;
  ui_.follow_map = false;
  ui_.view_from_keyframe = -1;
  ui_.camera = render::OrbitCamera::fromLookAt(eye, p, ui_.camera.up, ui_.camera.fov_y_deg);
}

void Workbench::frameTrajectories() {
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
    report(StatusLine::Kind::kWarning, "no trajectory yet to frame");
    return;
  }
  const glm::vec3 pad(0.05f);  // a straight path still gets a box
  ui_.camera.frame(lo - pad, hi + pad, static_cast<float>(ui_.view_width) / std::max(1, ui_.view_height));
  ui_.follow_map = false;  // a growing map must not take the view back
  ui_.view_from_keyframe = -1;
}

float Workbench::poseDragSpeed() const {
  const render::ViewCamera v = view(ui_.view_width, ui_.view_height).camera;
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

bool Workbench::takeScrollToSelected() { return std::exchange(ui_.scroll_to_selected, false); }

void Workbench::addMeasurePoint(const glm::vec3& point) {
  glm::vec3 p = point;
  if (ui_.measure_snap)
    if (const auto g = global(); g && !g->map.ellipsoids.empty()) {
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

bool Workbench::loadView(const std::string& file, bool thresholds) {
  if (!worker_) {
    report(StatusLine::Kind::kError, "Load view: nothing is open");
    return false;
  }
  const std::string path = absolute(file);
  render::ViewSpec spec;
  GlobalMapParams params = ui_.params.global;
  try {
    if (path.empty()) throw std::invalid_argument("Load view: type a file name first");
    spec = readViewFile(path, &params);
  } catch (const std::exception& e) {
    report(StatusLine::Kind::kError, e.what());
    return false;
  }
  if (!applyViewSpec(spec)) return false;
  if (thresholds) {
    ui_.params.global = params;
    applyThresholds();
  }
  if (!warnAboutTheViewsSize(spec))
    report(StatusLine::Kind::kSuccess, "view loaded from " + path + (thresholds ? " with its thresholds" : ""));
  return true;
}

bool Workbench::warnAboutTheViewsSize(const render::ViewSpec& asked) {
  // The view is drawn at the window's viewport, not at its own size: a size that differs gives
  // another picture than `vdmap render --view-file` (another aspect), so say so.
  const render::ViewSpec shown = viewSpec();
  if (asked.width <= 0 || (asked.width == shown.width && asked.height == shown.height)) return false;
  report(StatusLine::Kind::kWarning, "the view file's view is " + std::to_string(asked.width) + "x" +
                                         std::to_string(asked.height) + ", the window's " + std::to_string(shown.width) +
                                         "x" + std::to_string(shown.height) + " (--window-size changes it)");
  return true;
}

std::string Workbench::beforeOptimisationBanner(const MappingSnapshot& mapping) const {
  if (!ui_.show_before_optimisation) return "";
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
  std::snprintf(text, sizeof text, "BEFORE the last pose-graph optimisation (loop at frame %d, correction %s; B: after)",
                loop.position, render::metresText(loop.loop.correction_m).c_str());
  return text;
}

void Workbench::enableSettingsAutosave(std::string file, Settings at_start) {
  autosave_file_ = std::move(file);
  autosave_start_ = at_start;
  autosave_.emplace(std::move(at_start));
}

double Workbench::autosaveSettings(SettingsAutosave::Clock::time_point now) {
  if (!autosave_ || autosave_file_.empty()) return INFINITY;
  autosave_->note(now, ui_.settings);
  if (autosave_->due(now)) {
    try {
      saveChangedSettings(autosave_file_, autosave_start_, autosave_->noted());
    } catch (const std::exception& e) {
      report(StatusLine::Kind::kWarning, std::string("settings not saved: ") + e.what());
    }
    autosave_->saved();  // a failure is not retried every frame: the next change tries again
  }
  const auto left = autosave_->dueIn(now);
  return left ? std::chrono::duration<double>(*left).count() : INFINITY;
}

void Workbench::storeQuickView(int slot) {
  if (slot < 1 || slot > 9 || !worker_) return;
  quick_views_[static_cast<std::size_t>(slot - 1)] = viewSpec();
  report(StatusLine::Kind::kInfo, "view kept as quick view " + std::to_string(slot) + " (" + std::to_string(slot) +
                                      " shows it again)");
}

bool Workbench::recallQuickView(int slot) {
  if (slot < 1 || slot > 9 || !worker_) return false;
  const auto& spec = quick_views_[static_cast<std::size_t>(slot - 1)];
  if (!spec) {
    report(StatusLine::Kind::kInfo, "no quick view " + std::to_string(slot) + " yet (Ctrl+" + std::to_string(slot) +
                                        " keeps the view shown)");
    return false;
  }
  return applyViewSpec(*spec);
}

bool Workbench::saveViewSafely(const std::string& file, bool replace) {
  std::error_code ignored;
  std::string target = file;
  if (!replace && !file.empty() && fs::exists(file, ignored)) {
    if (fs::path(file).filename() == "vdmap_view.json") {
      target = freeNumberedName(file).string();  // the default name numbers itself
    } else {
      ui_.confirm_view_replace = absolute(file);
      report(StatusLine::Kind::kWarning, ui_.confirm_view_replace + " exists: replace it?");
      return false;
    }
  }
  ui_.confirm_view_replace.clear();
  return saveView(target);
}

}  // namespace vdmap::app::gui
