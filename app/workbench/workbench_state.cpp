#include "app/workbench/workbench_state.h"

#include <cmath>
#include <cstdio>
#include <filesystem>

namespace vdmap::app::gui {

std::string absolutePath(const std::string& path) {
  if (path.empty()) return path;
  std::error_code ignored;
  const std::filesystem::path p = std::filesystem::absolute(path, ignored);
  return (p.empty() ? std::filesystem::path(path) : p).lexically_normal().string();
}

void WorkbenchState::report(StatusLine::Kind kind, std::string text) {
  if (kind == StatusLine::Kind::kError && first_error.empty()) first_error = text;
  ui.status = {kind, std::move(text), ui.status.serial + 1};
}

std::string ProbeResult::text() const {
  char text[256];
  const char* name = occupancyName(state.state);
  // p below 0.0005 (free well in front of a surface) would print as 0.000: say "<0.001".
  const double p = state.p_occupied;
  int n = p < 0.0005 ? std::snprintf(text, sizeof text, "%s p<0.001", name)
                     : std::snprintf(text, sizeof text, "%s p=%.3f", name, p);
  const auto more = [&](const char* format, auto... args) {
    if (n >= 0 && n < static_cast<int>(sizeof text)) n += std::snprintf(text + n, sizeof text - n, format, args...);
  };
  if (std::isfinite(distance.distance_m)) more(" \u00b7 %.3f m to surface", distance.distance_m);
  else more(" \u00b7 no surface");
  if (state.state == Occupancy::kFree && state.keyframe >= 0) more(" (kf %d)", state.keyframe);
  more(" \u00b7 %.3f %.3f %.3f", static_cast<double>(point.x), static_cast<double>(point.y),
       static_cast<double>(point.z));
  std::string out = text;
  if (on_slice) out += " (slice)";
  if (!note.empty()) out += " \u00b7 " + note;
  return out;
}

}  // namespace vdmap::app::gui
