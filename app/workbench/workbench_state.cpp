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

bool DoubleClick::press(double t_s, double x, double y) {
  const bool second = t_s - last_t_ <= 0.4 && std::hypot(x - last_x_, y - last_y_) <= 6.0;
  last_t_ = second ? -1e9 : t_s;
  last_x_ = x;
  last_y_ = y;
  return second;
}

std::string breakLines(const std::string& text, float width, const std::function<float(std::string_view)>& measure) {
  std::string out, line;
  const auto endLine = [&] {
    while (!line.empty() && line.back() == ' ') line.pop_back();
    out += (out.empty() ? "" : "\n") + line;
    line.clear();
  };
  for (std::size_t start = 0; start < text.size();) {
    const std::size_t stop = text.find_first_of(" /\n", start);
    const std::size_t end = stop == std::string::npos ? text.size() : stop + 1;
    std::string piece = text.substr(start, end - start);
    start = end;
    if (piece.back() == '\n') {
      piece.pop_back();
      line += piece;
      endLine();
      continue;
    }
    if (!line.empty() && measure(line + piece) > width) endLine();
    for (const char c : piece) {  // a piece wider than a line alone: broken where it must
      if (!line.empty() && line.back() != ' ' && measure(line + c) > width && measure(piece) > width) endLine();
      line += c;
    }
  }
  if (!line.empty() || out.empty()) endLine();
  return out;
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
