#include "app/workbench/file_actions.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <utility>

#include "app/cli/error_text.h"
#include "app/cli/provenance.h"
#include "app/view/view_file.h"
#include "mapping/core/error.h"
#include "mapping/core/message_text.h"
#include "mapping/files/map_export.h"

namespace vdmap::app::gui {
namespace {

// "12 345" for the status line.
std::string grouped(std::size_t n) {
  std::string s = std::to_string(n);
  for (int i = static_cast<int>(s.size()) - 3; i > 0; i -= 3) s.insert(static_cast<std::size_t>(i), " ");
  return s;
}

// The frames of a saved session's sequence after its last one, for the player to continue
// with: none when the session cannot continue, its folder is gone, or its camera is not the
// session's. *off says why there are none (the Sequence panel shows it); *why too when it is
// worth a warning (not for a session mapped to its sequence's end).
std::optional<Sequence> framesAfter(const Session& saved, std::string* off, std::string* why) {
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
      const std::size_t listed = Sequence::open(info.sequence).listedDepthFrames();
      if (listed <= static_cast<std::size_t>(info.state.last_frame_index) + 1) {
        *off = "mapped to the end of " + info.sequence + " (" + std::to_string(info.state.last_frame_index + 1) +
               " of " + counted(static_cast<long long>(listed), "frame") + "): nothing to continue";
        return std::nullopt;
      }
    }
    SequenceOptions options;
    options.frames.first = info.state.last_frame_index + 1;
    Sequence rest = Sequence::open(info.sequence, options);
    if (!(rest.camera() == info.camera)) throw std::invalid_argument("its camera is not the session's");
    return rest;
  } catch (const std::exception& e) {
    *off = *why = "the player is off: the session's sequence " + info.sequence + " has no frames to continue with (" +
                  errorMessage(e) + ")";
    return std::nullopt;
  }
}

// The frames of a session's sequence, for their ground truth, when it was mapped with tracked
// poses and its folder has ground truth; none otherwise (the tracking error then stays hidden).
std::vector<FrameEntry> groundTruthOf(const SessionInfo& info) {
  if (info.mapper.poses != PoseSource::kTrack || !std::filesystem::is_directory(info.sequence)) return {};
  try {
    const Sequence seq = Sequence::open(info.sequence);
    if (seq.hasGroundTruth()) return seq.entries();
  } catch (const std::exception&) {  // framesAfter says what is wrong with the folder
  }
  return {};
}

}  // namespace

bool FileActions::open(const SequenceArgs& args) {
  SequenceArgs absolute_args = args;
  absolute_args.folder = absolutePath(args.folder);
  try {
    Sequence sequence = openSequence(absolute_args);
    // The pose source belongs to the sequence (--poses, or whether it has ground truth), not
    // to the settings; re-runs keep it.
    MapperParams mapper = ui_.settings.mapper;
    mapper.poses = poseSource(absolute_args, sequence);
    auto worker = std::make_unique<MappingWorker>(std::move(sequence), mapper, ui_.settings.thresholds, refine_);
    worker->setOnChange(state_.on_change);
    worker->setFps(ui_.settings.play_fps);
    worker_ = std::move(worker);  // the old session (if any) stops here
    ui_.params = {mapper, ui_.settings.thresholds};
    why_player_off_.clear();
    state_.opened_args = absolute_args;  // what a printed render command repeats, with this run's refinement
    state_.opened_args.refine = !refine_                                            ? "none"
                                : refine_->method == MapRefinementMethod::kPairwise ? "pairwise"
                                                                                    : "joint";
    state_.opened_args.refine_given = state_.opened_args.refine != SequenceArgs{}.refine;
    state_.render_thresholds = GlobalMapParams{};
  } catch (const std::exception& e) {
    state_.report(StatusLine::Kind::kError, errorMessage(e));
    return false;
  }
  opened(absolute_args.folder);
  return true;
}

bool FileActions::openSession(const std::string& file) {
  const std::string path = absolutePath(file);
  std::string why;
  try {
    Session saved = loadSession(path);
    // The session's own parameters, shown and used; the user's settings stay as they are.
    ParameterValues params{saved.info.mapper, saved.info.global};
    const GlobalMapParams saved_thresholds = saved.info.global;
    Settings over;  // keys the file and --set lack keep the session's values
    over.thresholds = params.global;
    if (!session_settings_.empty()) over = readSettingsArg(session_settings_, over);
    for (const std::string& kv : session_set_) applySetting(over, kv);
    params.global = over.thresholds;
    std::string off;
    std::optional<Sequence> rest = framesAfter(saved, &off, &why);
    std::vector<FrameEntry> truth = groundTruthOf(saved.info);
    auto worker =
        std::make_unique<MappingWorker>(std::move(saved), params.global, std::move(rest), refine_, std::move(truth));
    worker->setOnChange(state_.on_change);
    worker_ = std::move(worker);
    ui_.params = params;
    why_player_off_ = off;
    state_.opened_args = {};
    state_.render_thresholds = saved_thresholds;
  } catch (const std::exception& e) {
    state_.report(StatusLine::Kind::kError, errorMessage(e));
    return false;
  }
  opened(path);
  if (!why.empty()) state_.report(StatusLine::Kind::kWarning, why);
  return true;
}

bool FileActions::openPath(const std::string& path_in) {
  if (path_in.empty()) return false;
  const std::string path = absolutePath(path_in);
  MapFileKind kind;
  try {
    kind = detectMapFile(path);
  } catch (const std::exception& e) {
    state_.report(StatusLine::Kind::kError, errorMessage(e));
    return false;
  }
  bool ok = false;
  switch (kind) {
    case MapFileKind::kSequence: ok = open({.folder = path}); break;
    case MapFileKind::kSession: ok = openSession(path); break;
    case MapFileKind::kViewFile:
      try {
        // As Load view: its camera and view options, not its thresholds (those apply only
        // through --settings).
        const bool whole = view_.applySpec(readViewFile(path));
        state_.report(whole ? StatusLine::Kind::kSuccess : StatusLine::Kind::kWarning,
                      "view " + path + " applied" + (whole ? "" : " (its keyframe is not mapped: the global view)"));
        ok = true;
        addRecent(ui_.settings, path);  // opened() remembers the other kinds
      } catch (const std::exception& e) {
        state_.report(StatusLine::Kind::kError, errorMessage(e));
      }
      break;
    default: ok = openMapFile(path); break;
  }
  return ok;
}

bool FileActions::openMapFile(const std::string& path_in) {
  const std::string path = absolutePath(path_in);
  try {
    return openMapFile(std::make_shared<const StaticMap>(loadStaticMap(path)));
  } catch (const std::exception& e) {
    state_.report(StatusLine::Kind::kError, errorMessage(e));
    return false;
  }
}

bool FileActions::openMapFile(std::shared_ptr<const StaticMap> map) {
  const StaticMap& m = *map;
  auto worker = std::make_unique<MappingWorker>(map);
  worker->setOnChange(state_.on_change);
  worker_ = std::move(worker);
  // The sliders (disabled) show what the worker holds, so nothing reads as pending.
  ui_.params = {worker_->mapping()->mapper, worker_->global()->params};
  why_player_off_ = kStaticMapWhy;
  state_.opened_args = {};
  state_.render_thresholds.reset();
  opened(m.path.string());
  // A file without colours is drawn by height: the colour mode says so and the legend shows the
  // ramp, rather than "rgb" over colours the file does not have.
  if (m.height_colors && ui_.settings.color == render::ColorMode::kRgb) {
    ui_.settings.color = render::ColorMode::kHeight;
    height_for_rgb_ = true;
  }
  char sigma[32];
  std::snprintf(sigma, sizeof sigma, "%.1f mm", m.sigma_m * 1e3);
  std::string what = std::string(mapFileKindName(m.kind)) + ", " + grouped(m.ellipsoids.size()) +
                     (m.kind == MapFileKind::kOctomap ? " occupied leaves" : " ellipsoids");
  if (m.kind == MapFileKind::kPointPly) what += std::string(", points drawn at sigma ") + sigma;
  if (m.kind == MapFileKind::kOctomap) what += std::string(", resolution ") + sigma;
  if (!m.keyframes.empty()) what += ", " + counted(static_cast<long long>(m.keyframes.size()), "keyframe");
  state_.report(StatusLine::Kind::kSuccess, "opened " + m.path.string() + " (" + what + ")");
  return true;
}

Settings FileActions::savedSettings() const {
  Settings s = ui_.settings;
  if (height_for_rgb_ && s.color == render::ColorMode::kHeight) s.color = render::ColorMode::kRgb;
  return s;
}

int FileActions::openDropped() {
  std::vector<std::string> paths;
  paths.swap(dropped_);
  for (const std::string& p : paths) openPath(p);
  return static_cast<int>(paths.size());
}

void FileActions::opened(const std::string& path) {
  ++state_.session_serial;
  state_.edit_diff.reset();
  if (std::exchange(height_for_rgb_, false) && ui_.settings.color == render::ColorMode::kHeight)
    ui_.settings.color = render::ColorMode::kRgb;  // as it was before a file without colours
  ui_.settings.last_sequence = path;
  addRecent(ui_.settings, path);  // however it was opened: the command line, Open, a drop, Recent
  ui_.sequence_text = path;
  state_.report(StatusLine::Kind::kSuccess, "opened " + path);
  ui_.selected_keyframe = ui_.view_from_keyframe = -1;  // as the new session's selection
  ui_.picked.reset();
  ui_.measure_a.reset();  // a measurement belongs to the map it was made on
  ui_.measure_b.reset();
  ui_.follow_map = true;
  ui_.show_before_optimisation = false;  // as the new session's
  opened_();
}

void FileActions::exportMap() {
  if (!worker_) return;
  const std::string dir = absolutePath(ui_.export_text);
  // What `vdmap map` writes, for the frames mapped so far: the trajectory and how the map was
  // made (provenance.h). The sequence outlives the worker's commands.
  const Sequence* seq = worker_->sequence();
  const std::string session = seq ? "" : ui_.settings.last_sequence;  // the .vdmap file opened
  worker_->withMapper([dir, seq, session, refine = refine_](const Mapper& mapper, const GlobalSnapshot& global) {
    MapExportOptions options;
    options.trajectory = mapper.trajectory();
    options.run_stats = {{"frames", mapper.framesMapped()}, {"source", "vdmap workbench"}};
    if (seq) {
      // The range the player has reached: from the sequence's first frame to the last one mapped.
      const int last = mapper.state().last_frame_index;
      options.run_stats["frame_range"] =
          frameRangeText({seq->frameRange().first, std::max(last + 1, seq->frameRange().first)});
      options.run_stats.update(frameCounts(*seq));
      options.run_stats.erase("frames_mapped");  // of the whole range, which the player may not have reached
    }
    options.run_stats.update(provenanceStats({seq ? seq->folder().string() : std::string(),
                                              seq ? seq->cameraSource() : "session " + session,
                                              mapper.camera(),
                                              mapper.params().poses,
                                              refine,
                                              {mapper.params(), global.params}}));
    vdmap::exportMap(dir, mapper.graph(), global.map, options);
    return "exported the map into " + dir;
  });
}

void FileActions::saveSession() {
  if (!worker_) return;
  const std::string file = absolutePath(ui_.session_text);
  // The session remembers its sequence, so that it can be continued (vdmap map --load, Open).
  const std::string folder = worker_->sequenceFolder();
  worker_->withMapper([file, folder](const Mapper& mapper, const GlobalSnapshot& global) {
    vdmap::saveSession(file, mapper.graph(), sessionInfo(mapper, global.params, folder));
    return "saved the session to " + file;
  });
}

void FileActions::loadTrajectory() {
  if (worker_) worker_->loadTrajectory(absolutePath(ui_.trajectory_text));
}

}  // namespace vdmap::app::gui
