// Opening files in the workbench (docs/workbench.md "Opening files"): whatever a path holds
// (mapping/files/map_file.h) opens as a sequence, a session, a static map or a view; drops queue
// here and the next frame opens them; opened paths go to the recent list.
#include <cstdio>
#include <filesystem>

#include "app/workbench/workbench.h"
#include "app/view/view_file.h"
#include "mapping/core/error.h"

namespace vdmap::app::gui {
namespace fs = std::filesystem;
namespace {

std::string absolutePath(const std::string& path) {
  std::error_code ignored;
  const fs::path p = fs::absolute(path, ignored);
  return (p.empty() ? fs::path(path) : p).lexically_normal().string();
}

// "12 345" for the status line.
std::string grouped(std::size_t n) {
  std::string s = std::to_string(n);
  for (int i = static_cast<int>(s.size()) - 3; i > 0; i -= 3) s.insert(static_cast<std::size_t>(i), " ");
  return s;
}

}  // namespace

bool Workbench::openPath(const std::string& path_in) {
  if (path_in.empty()) return false;
  const std::string path = absolutePath(path_in);
  MapFileKind kind;
  try {
    kind = detectMapFile(path);
  } catch (const std::exception& e) {
    report(StatusLine::Kind::kError, e.what());
    return false;
  }
  bool ok = false;
  switch (kind) {
    case MapFileKind::kSequence: ok = open({path, "", "", ""}); break;
    case MapFileKind::kSession: ok = openSession(path); break;
    case MapFileKind::kViewFile:
      try {
        // As Load view: its camera and view options, not its thresholds (those apply only
        // through --settings).
        const bool whole = applyViewSpec(readViewFile(path));
        report(whole ? StatusLine::Kind::kSuccess : StatusLine::Kind::kWarning,
               "view " + path + " applied" + (whole ? "" : " (its keyframe is not mapped: the global view)"));
        ok = true;
      } catch (const std::exception& e) {
        report(StatusLine::Kind::kError, e.what());
      }
      break;
    default: ok = openMapFile(path); break;
  }
  if (ok) addRecent(ui_.settings, path);
  return ok;
}

bool Workbench::openMapFile(const std::string& path_in) {
  const std::string path = absolutePath(path_in);
  try {
    return openMapFile(std::make_shared<const StaticMap>(loadStaticMap(path)));
  } catch (const std::exception& e) {
    report(StatusLine::Kind::kError, e.what());
    return false;
  }
}

bool Workbench::openMapFile(std::shared_ptr<const StaticMap> map) {
  const StaticMap& m = *map;
  auto worker = std::make_unique<MappingWorker>(map);
  worker->setOnChange(on_change_);
  worker_ = std::move(worker);
  // The sliders (disabled) show what the worker holds, so nothing reads as pending.
  ui_.params = {worker_->mapping()->mapper, worker_->global()->params};
  why_player_off_ = kStaticMapWhy;
  opened(m.path.string());
  char sigma[32];
  std::snprintf(sigma, sizeof sigma, "%.1f mm", m.sigma_m * 1e3);
  std::string what = std::string(mapFileKindName(m.kind)) + ", " + grouped(m.ellipsoids.size()) +
                     (m.kind == MapFileKind::kOctomap ? " occupied leaves" : " ellipsoids");
  if (m.kind == MapFileKind::kPointPly) what += std::string(", points drawn at sigma ") + sigma;
  if (m.kind == MapFileKind::kOctomap) what += std::string(", resolution ") + sigma;
  if (!m.keyframes.empty()) what += ", " + std::to_string(m.keyframes.size()) + " keyframes";
  report(StatusLine::Kind::kSuccess, "opened " + m.path.string() + " (" + what + ")");
  return true;
}

int Workbench::openDropped() {
  std::vector<std::string> paths;
  paths.swap(dropped_);
  for (const std::string& p : paths) openPath(p);
  return static_cast<int>(paths.size());
}

}  // namespace vdmap::app::gui
