#include "app/workbench/view_files.h"

#include <cstdlib>
#include <iostream>

#include "app/cli/command_line.h"
#include "app/cli/error_text.h"
#include "app/cli/mesh_options.h"
#include "app/cli/parameter_table.h"
#include "app/view/view_file.h"

namespace vdmap::app::gui {
namespace fs = std::filesystem;

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

bool ViewFiles::load(const std::string& file, bool thresholds) {
  if (!state_.worker) {
    state_.report(StatusLine::Kind::kError, "Load view: nothing is open");
    return false;
  }
  const std::string path = absolutePath(file);
  render::ViewSpec spec;
  GlobalMapParams params = state_.ui.params.global;
  try {
    if (path.empty()) throw std::invalid_argument("Load view: type a file name first");
    spec = readViewFile(path, &params);
  } catch (const std::exception& e) {
    state_.report(StatusLine::Kind::kError, errorMessage(e));
    return false;
  }
  if (!view_.applySpec(spec)) return false;
  if (thresholds) {
    state_.ui.params.global = params;
    parameters_.applyThresholds();
  }
  if (!warnAboutSize(spec))
    state_.report(StatusLine::Kind::kSuccess, "view loaded from " + path + (thresholds ? " with its thresholds" : ""));
  return true;
}

bool ViewFiles::save(const std::string& file) {
  if (!state_.worker) {
    state_.report(StatusLine::Kind::kError, "Save view: nothing is open");
    return false;
  }
  const std::string path = absolutePath(file);
  try {
    if (path.empty()) throw std::invalid_argument("Save view: type a file name first");
    writeViewFile(path, view_.spec(), state_.ui.params.global, source());
  } catch (const std::exception& e) {
    state_.report(StatusLine::Kind::kError, errorMessage(e));
    return false;
  }
  const std::string command = renderCommand(view_.spec(), commandSource(), path);
  std::cout << "vdmap: view saved to " << path << "; draw it with: " << command << std::endl;
  state_.report(StatusLine::Kind::kSuccess, "view saved to " + path + "; " + command);
  return true;
}

namespace {

// " --set KEY=VALUE" for each parameter (live ones when `live`) whose value in `now` is not its
// value in `start`.
std::string changedParameters(const ParameterValues& now, const ParameterValues& start, bool live) {
  std::string sets;
  for (const Parameter& p : parameters()) {
    if (p.live != live || p.get(now) == p.get(start)) continue;
    const double v = p.get(now);
    const std::string text = p.kind == ParameterSpec::Kind::kChoice ? formatValue(p, v) : valueJson(p, v).dump();
    sets += " --set " + shellQuoted(std::string(p.key) + "=" + text);
  }
  return sets;
}

}  // namespace

CommandSource ViewFiles::commandSource() const {
  CommandSource out(source());
  const MappingWorker* worker = state_.worker.get();
  const auto mapping = worker ? worker->mapping() : nullptr;
  if (!mapping) return out;
  if (const Sequence* seq = worker->sequence(); seq && !state_.opened_args.folder.empty()) {
    SequenceArgs args = state_.opened_args;
    const int mapped = mapping->frames_mapped;
    const bool whole = mapped >= static_cast<int>(seq->size());
    if (mapped > 0 && !whole)  // the frames the player has reached
      args.frames = frameRangeText({seq->frameRange().first, seq->entries()[mapped - 1].index + 1});
    const bool tracked = mapping->mapper.poses == PoseSource::kTrack;
    args.poses = tracked ? "track" : "gt";
    if (!tracked) args.refine_given = false;                          // refinement corrects tracked poses only
    else if (!whole) args.refine = "none", args.refine_given = true;  // refined after the last frame
    out.flags = sequenceFlags(args) + changedParameters({mapping->mapper, {}}, {MapperParams{}, {}}, false);
  }
  if (state_.ui.settings.show_mesh) out.flags += meshFlags(state_.ui.settings.mesh);  // how its mesh is made
  if (state_.render_thresholds)
    out.thresholds = changedParameters({{}, state_.ui.params.global}, {{}, *state_.render_thresholds}, true);
  return out;
}

bool ViewFiles::saveSafely(const std::string& file, bool replace) {
  std::error_code ignored;
  std::string target = file;
  if (!replace && !file.empty() && fs::exists(file, ignored)) {
    if (fs::path(file).filename() == "vdmap_view.json") {
      target = freeNumberedName(file).string();  // the default name numbers itself
    } else {
      state_.ui.confirm_view_replace = absolutePath(file);
      state_.report(StatusLine::Kind::kWarning, state_.ui.confirm_view_replace + " exists: replace it?");
      return false;
    }
  }
  state_.ui.confirm_view_replace.clear();
  return save(target);
}

bool ViewFiles::warnAboutSize(const render::ViewSpec& asked) {
  // The view is drawn at the window's viewport, not at its own size: a size that differs gives
  // another picture than `vdmap render --view-file` (another aspect), so say so.
  const render::ViewSpec shown = view_.spec();
  if (asked.width <= 0 || (asked.width == shown.width && asked.height == shown.height)) return false;
  state_.report(StatusLine::Kind::kWarning, "the view file's view is " + std::to_string(asked.width) + "x" +
                                                std::to_string(asked.height) + ", the window's " +
                                                std::to_string(shown.width) + "x" + std::to_string(shown.height) +
                                                " (--window-size changes it)");
  return true;
}

fs::path ViewFiles::quickViewFile(int slot) const {
  return quick_view_folder_.empty() ? fs::path()
                                    : quick_view_folder_ / "quick_views" / (std::to_string(slot) + ".json");
}

void ViewFiles::storeQuickView(int slot) {
  if (slot < 1 || slot > 9 || !state_.worker) return;
  const render::ViewSpec spec = view_.spec();
  quick_views_[static_cast<std::size_t>(slot - 1)] = spec;
  std::string kept =
      "view kept as quick view " + std::to_string(slot) + " (" + std::to_string(slot) + " shows it again)";
  if (const fs::path file = quickViewFile(slot); !file.empty()) {
    try {
      fs::create_directories(file.parent_path());
      writeViewFile(file, spec, state_.ui.params.global, source());
    } catch (const std::exception& e) {
      return state_.report(StatusLine::Kind::kWarning, kept + ", for this run only: " + errorMessage(e));
    }
  }
  state_.report(StatusLine::Kind::kInfo, kept);
}

bool ViewFiles::recallQuickView(int slot) {
  if (slot < 1 || slot > 9 || !state_.worker) return false;
  auto& spec = quick_views_[static_cast<std::size_t>(slot - 1)];
  const fs::path file = quickViewFile(slot);
  std::error_code ignored;
  if (!spec && !file.empty() && fs::exists(file, ignored)) {  // kept by an earlier run
    try {
      spec = readViewFile(file);
    } catch (const std::exception& e) {
      state_.report(StatusLine::Kind::kWarning,
                    std::string("quick view ") + std::to_string(slot) + ": " + errorMessage(e));
      return false;
    }
  }
  if (!spec) {
    state_.report(StatusLine::Kind::kInfo, "no quick view " + std::to_string(slot) + " yet (Ctrl+" +
                                               std::to_string(slot) + " keeps the view shown)");
    return false;
  }
  return view_.applySpec(*spec);
}

}  // namespace vdmap::app::gui
